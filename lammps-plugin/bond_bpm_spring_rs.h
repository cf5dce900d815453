/* bond_style bpm/spring/rs and bpm/spring/plastic/rs: upstream LAMMPS's
 * bpm/spring and bpm/spring/plastic on our kernels, with their syntax, so
 * that an upstream deck runs unchanged under -sf rs:
 *
 *   bond_style bpm/spring/rs [break yes|no] [smooth yes|no] [normalize yes|no]
 *       [volume/factor yes|no] [overlay/pair yes|no] [store/local ID N values...]
 *   bond_coeff T k epsilon_c gamma [a_v]                  (a_v with volume/factor)
 *   bond_style bpm/spring/plastic/rs ... (the same keywords)
 *   bond_coeff T k epsilon_c gamma epsilon_p [a_v]
 *
 * Bonds break at strain epsilon_c and yield at epsilon_p (docs/model.md,
 * "Breaking and yielding"); the plastic style also takes the multibody
 * volume term, which upstream's lacks. A broken bond leaves its atoms'
 * bond arrays at once and its pair becomes a contact from the next force
 * evaluation (FixBPMBrokenPairs). All physics is in the Rust kernels. */
#ifndef LMP_BOND_BPM_SPRING_RS_H
#define LMP_BOND_BPM_SPRING_RS_H

#include "bond.h"
#include "bpm_kernels.h"
#include <string>
#include <vector>

namespace LAMMPS_NS {

class BondBPMSpringRS : public Bond {
 public:
  BondBPMSpringRS(class LAMMPS *, bool plastic);
  ~BondBPMSpringRS() override;
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
  const bool plastic;
  const std::string style;
  int break_flag, smooth, normalize, volume, overlay;
  std::vector<bpm_bond_coeffs> coeffs;    // index: type - 1
  std::vector<bpm_bond_failure> rules;    // index: type - 1
  std::vector<char> with_volume;          // index: type - 1: a_v was given
  bool damped, live;
  std::vector<int32_t> broken;
  std::string store_id;                   // store/local: fix ID, interval, values
  int store_every;
  std::vector<std::string> store_values;
  std::vector<double> store_row;
  // The list's intact bonds as rows between neighbour builds (one bond
  // type, steps without energy or virial): the faster pass.
  bpm_list_rows *rows;
  bigint list_edits;    // list-kernel steps that broke or yielded bonds: the rows are rebuilt after one
  class FixBPMReference *reference;
  class FixBPMBrokenPairs *broken_pairs;
  class FixBPMStoreLocal *store;
  void allocate();
  void apply_flags();
  void ensure_fixes();
  void check_special_weights();
  void process_broken(int i, int j);
  void forget_bond(int i, int j);
  bpm_failure_counts compute_rows(bpm_bond_entry *bonds, const double *r0, double *plastic_strains,
                                  int ngather, bpm_fault &fault, int &status);
  void settle_failures(const bpm_failure_counts &found);
};

}    // namespace LAMMPS_NS

#endif
