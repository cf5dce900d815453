/* The styles' internal fixes: found by ID, or made if missing, so that a
 * style re-issued (or re-made after read_restart) keeps its fix and the
 * data the fix holds. */
#ifndef BPM_INTERNAL_FIX_H
#define BPM_INTERNAL_FIX_H

#include "error.h"
#include "lammps.h"
#include "modify.h"

#include <string>

// The fix with ID `id`, of class F; made with "`id` all `command`" if no
// fix has the ID. An error if another kind of fix holds it.
template <class F>
F *bpm_internal_fix(LAMMPS_NS::LAMMPS *lmp, const std::string &id, const std::string &command)
{
  auto modify = lmp->modify;
  int ifix = modify->find_fix(id);
  if (ifix < 0) {
    modify->add_fix(id + " all " + command);
    ifix = modify->find_fix(id);
  }
  auto fix = dynamic_cast<F *>(modify->fix[ifix]);
  if (!fix) lmp->error->all(FLERR, "fix ID " + id + " is taken by another fix");
  return fix;
}

#endif
