/* Internal fix of bond_style bpm/spring/rs ... store/local ID N values:
 * the rows of the bonds broken since the last output, as a local vector
 * (one value) or array, for dump local and compute reduce. Every N steps
 * the rows gathered so far become the output and gathering starts over,
 * as upstream LAMMPS's fix STORE/LOCAL does. Created by the bond style. */
#ifndef LMP_FIX_BPM_STORE_LOCAL_H
#define LMP_FIX_BPM_STORE_LOCAL_H

#include "fix.h"
#include <vector>

namespace LAMMPS_NS {

class FixBPMStoreLocal : public Fix {
 public:
  FixBPMStoreLocal(class LAMMPS *, int, char **);
  ~FixBPMStoreLocal() override;
  int setmask() override;
  void post_force(int) override;
  double memory_usage() override;

  int values() const { return nvalues; }
  int every() const { return nreset; }
  // One row of values() numbers for the bond between atoms i and j (kept
  // only if both are in the fix's group).
  void add(const double *row, int i, int j);

 private:
  int nreset, nvalues, nmax, count;
  double *vector;
  double **array;
};

}    // namespace LAMMPS_NS

#endif
