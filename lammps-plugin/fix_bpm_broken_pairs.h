/* Internal fix of bond_style bpm/spring/rs: a broken bond's pair becomes a
 * contact, as upstream LAMMPS's fix update/special/bonds makes it. From the
 * next force evaluation on, the pair loses its 1-2 special bits in the
 * neighbour lists (pre_force); at the next reneighbouring, each owned
 * atom's special list loses the partner (pre_exchange), so rebuilt lists
 * hold the pair as a plain one. Needs special_bonds lj 0 1 1 coul 1 1 1
 * (only 1-2 lists) and newton_bond off (each rank sees its atoms' breaks).
 * Created by the bond style with ID BPM_BROKEN_PAIRS. */
#ifndef LMP_FIX_BPM_BROKEN_PAIRS_H
#define LMP_FIX_BPM_BROKEN_PAIRS_H

#include "fix.h"
#include <utility>
#include <vector>

namespace LAMMPS_NS {

class FixBPMBrokenPairs : public Fix {
 public:
  FixBPMBrokenPairs(class LAMMPS *, int, char **);
  int setmask() override;
  void pre_exchange() override;
  void pre_force(int) override;
  // A run's set-up rebuilds the lists: breaks since the last reneighbouring
  // must leave the special lists first, and the lists after.
  void setup_pre_exchange() override { pre_exchange(); }
  void setup_pre_force(int vflag) override { pre_force(vflag); }
  void min_pre_exchange() override { pre_exchange(); }
  void min_pre_force(int vflag) override { pre_force(vflag); }

  // The bond between atoms i and j (local or ghost) broke.
  void add(int i, int j);

 private:
  std::vector<std::pair<tagint, tagint>> unlisted;      // not yet out of the neighbour lists
  std::vector<std::pair<tagint, tagint>> unspecial;     // not yet out of the special lists
  void forget_partner(int i, tagint partner);
};

}    // namespace LAMMPS_NS

#endif
