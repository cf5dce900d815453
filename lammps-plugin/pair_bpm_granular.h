/* pair_style bpm/granular: DEM sphere contacts (Hertz-Mindlin with damping,
 * sliding, rolling and twisting friction) with the optional multi-contact
 * closure (docs/model.md). Physics in the Rust kernels; this class passes
 * LAMMPS's arrays and neighbour list, and its fix BPM/CONTACTS stores and
 * moves the per-atom contact rows. */
#ifndef LMP_PAIR_BPM_GRANULAR_H
#define LMP_PAIR_BPM_GRANULAR_H

#include "pair.h"
#include "bpm_kernels.h"
#include <string>
#include <vector>

namespace LAMMPS_NS {

class PairBPMGranular : public Pair {
 public:
  PairBPMGranular(class LAMMPS *);
  ~PairBPMGranular() override;
  void compute(int, int) override;
  void settings(int, char **) override;
  void coeff(int, char **) override;
  void init_style() override;
  double init_one(int, int) override;
  void write_restart(FILE *) override;
  void read_restart(FILE *) override;

 protected:
  bpm_granular *style;
  std::vector<std::string> words;    // pair_coeff after "* *", for restarts
  std::vector<int64_t> tags;
  class FixBPMContacts *contacts;
  std::vector<class FixBPMGranularWall *> walls;    // fix bpm/granular/wall, found each evaluation
  std::vector<bpm_granular_wall> wall_state;
  std::vector<double> wall_forces;
  double max_radius;
  void allocate();
  void create_style();
  void ensure_contacts();
  void set_walls();
  void stop(const char *pass, int status, const char *message);
};

}    // namespace LAMMPS_NS

#endif
