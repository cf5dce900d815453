/* Stops a run whose kernels reported a fault (BPM_ERR_UNSTABLE): the message,
 * worded by the kernels, names the step, the atoms by their IDs and the
 * likely cause. error->one: the rank that found it stops the run. */
#ifndef LMP_BPM_FAULT_MESSAGE_H
#define LMP_BPM_FAULT_MESSAGE_H

#include "atom.h"
#include "bpm_kernels.h"
#include "error.h"
#include "update.h"

#include <string>

namespace LAMMPS_NS {

static_assert(sizeof(bpm_fault) == 56, "bpm_fault must match the Rust Fault layout (src/ffi.rs)");

inline void bpm_stop_on_fault(LAMMPS *lmp, const char *style, const bpm_fault &fault,
                              const bpm_bond_coeffs *bond)
{
  char text[1024];
  const Atom *atom = lmp->atom;
  double mass = atom->rmass ? atom->rmass[fault.i] : atom->mass[atom->type[fault.i]];
  int64_t n = bpm_describe_fault(&fault, (int64_t) atom->tag[fault.i], (int64_t) atom->tag[fault.j],
                                 (int64_t) lmp->update->ntimestep, lmp->update->dt, bond, mass,
                                 text, (int64_t) sizeof(text));
  std::string message = std::string(style) + ": ";
  message += n >= 0 ? std::string(text) : "unstable (fault not described: status " + std::to_string(-n) + ")";
  lmp->error->one(FLERR, message);
}

}    // namespace LAMMPS_NS

#endif
