/* bond_style bpm/multibody: spring + multibody volume term + damping
 * (docs/model.md). All physics is in the Rust kernels (bpm_kernels.h);
 * this class parses coefficients, keeps the reference lengths (through
 * FixBPMReference) and hands LAMMPS's bond list to the kernels. */
#ifndef LMP_BOND_BPM_MULTIBODY_H
#define LMP_BOND_BPM_MULTIBODY_H

#include "bond.h"
#include "bpm_kernels.h"
#include <vector>

namespace LAMMPS_NS {

class BondBPMMultibody : public Bond {
 public:
  BondBPMMultibody(class LAMMPS *);
  ~BondBPMMultibody() override;
  void compute(int, int) override;
  void coeff(int, char **) override;
  void init_style() override;
  void settings(int, char **) override;
  double equilibrium_distance(int) override;
  void write_restart(FILE *) override;
  void read_restart(FILE *) override;
  void write_data(FILE *) override;
  double single(int, double, int, int, double &) override;

 protected:
  std::vector<bpm_bond_coeffs> coeffs;    // index: type - 1
  class FixBPMReference *reference;
  bool multibody, damped;
  bool zero_net;    // the zero-net-multibody variant (keyword zero_net)
  void allocate();
  void apply_zero_net_correction(const bpm_bond_entry *, int, const double *, int, int, int);
  void ensure_reference();
};

}    // namespace LAMMPS_NS

#endif
