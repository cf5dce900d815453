/* pair_style bpm/contact: harmonic + cubic repulsion + damping between
 * non-bonded particles closer than d (docs/model.md). Physics in the Rust
 * kernels; bonded pairs are excluded with special_bonds lj 0 1 1. */
#ifndef LMP_PAIR_BPM_CONTACT_H
#define LMP_PAIR_BPM_CONTACT_H

#include "pair.h"
#include "bpm_kernels.h"
#include <string>
#include <vector>

namespace LAMMPS_NS {

class PairBPMContact : public Pair {
 public:
  PairBPMContact(class LAMMPS *);
  ~PairBPMContact() override;
  void compute(int, int) override;
  void settings(int, char **) override;
  void coeff(int, char **) override;
  void init_style() override;
  double init_one(int, int) override;
  void write_restart(FILE *) override;
  void read_restart(FILE *) override;
  void write_data(FILE *) override;
  void write_data_all(FILE *) override;

 protected:
  std::vector<bpm_pair_coeffs> table;    // (i-1) * ntypes + (j-1)
  bool damped;
  bool damping_taper;    // upstream's fading contact damping (bpm/spring/rs)
  std::string style;     // in messages: "pair_style bpm/contact"
  void allocate();
  void set_coeffs(char **, const bpm_pair_coeffs &);
  void check_ghost_velocities();
};

}    // namespace LAMMPS_NS

#endif
