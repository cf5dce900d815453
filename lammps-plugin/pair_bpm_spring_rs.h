/* pair_style bpm/spring/rs: upstream LAMMPS's pair_style bpm/spring on our
 * kernels, with its syntax: "pair_style bpm/spring/rs [anharmonic yes|no]",
 * "pair_coeff I J k r_c gamma [k_a]" (k_a with anharmonic yes). The force
 * is our contact (docs/model.md) with contact distance r_c, cubic term k_a,
 * and upstream's damping, which fades as 1 - (r/r_c)^8. LAMMPS's -sf rs
 * picks it for a deck's bpm/spring. */
#ifndef LMP_PAIR_BPM_SPRING_RS_H
#define LMP_PAIR_BPM_SPRING_RS_H

#include "pair_bpm_contact.h"

namespace LAMMPS_NS {

class PairBPMSpringRS : public PairBPMContact {
 public:
  PairBPMSpringRS(class LAMMPS *);
  void settings(int, char **) override;
  void coeff(int, char **) override;
  void init_style() override;
  void write_restart(FILE *) override;
  void read_restart(FILE *) override;
  void write_data(FILE *) override;
  void write_data_all(FILE *) override;

 protected:
  bool anharmonic;
};

}    // namespace LAMMPS_NS

#endif
