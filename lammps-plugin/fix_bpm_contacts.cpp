#include "fmt_compat.h"

#include "fix_bpm_contacts.h"

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "memory.h"
#include "utils.h"

#include <cstring>
#include <string>

using namespace LAMMPS_NS;
using namespace FixConst;

FixBPMContacts::FixBPMContacts(LAMMPS *lmp, int narg, char **arg) :
    Fix(lmp, narg, arg), rows(nullptr), nmax_rows(0), corrections(nullptr), ncorrections(0)
{
  if (narg != 4) error->all(FLERR, std::string("Illegal fix BPM/CONTACTS command: it takes the slots per atom"));
  nslots = utils::inumeric(FLERR, arg[3], false, lmp);
  if (nslots < 1) error->all(FLERR, std::string("fix BPM/CONTACTS: slots must be at least 1"));
  memory_stride = 1 + 9 * nslots;
  correction_stride = 1 + 2 * nslots;
  restart_peratom = 1;
  create_attribute = 1;
  stores_ids = 1;                   // partner IDs: reset_atoms id would scramble them
  maxexchange = memory_stride;      // one atom's row in Comm::exchange()
  comm_forward = correction_stride;
  grow_arrays(atom->nmax);
  atom->add_callback(Atom::GROW);
  atom->add_callback(Atom::RESTART);
}

FixBPMContacts::~FixBPMContacts()
{
  atom->delete_callback(id, Atom::GROW);
  atom->delete_callback(id, Atom::RESTART);
  memory->destroy(rows);
  memory->destroy(corrections);
}

int FixBPMContacts::setmask()
{
  return 0;
}

double *FixBPMContacts::correction_rows(int nall)
{
  if (nall > ncorrections) {
    int before = ncorrections;
    ncorrections = atom->nmax > nall ? atom->nmax : nall;
    memory->grow(corrections, (bigint) ncorrections * correction_stride, "bpm/contacts:corrections");
    for (int i = before; i < ncorrections; i++) corrections[(bigint) i * correction_stride] = 0.0;
  }
  return corrections;
}

void FixBPMContacts::forward_corrections()
{
#if defined(BPM_MODERN_LAMMPS)    // 2022 and later: comm calls overloaded by class
  comm->forward_comm(this);
#else
  comm->forward_comm_fix(this);
#endif
}

int FixBPMContacts::pack_forward_comm(int n, int *list, double *buf, int, int *)
{
  int m = 0;
  for (int k = 0; k < n; k++) {
    std::memcpy(buf + m, corrections + (bigint) list[k] * correction_stride, sizeof(double) * correction_stride);
    m += correction_stride;
  }
  return m;
}

// The pair style sized the rows for every ghost before the copy.
void FixBPMContacts::unpack_forward_comm(int n, int first, double *buf)
{
  std::memcpy(corrections + (bigint) first * correction_stride, buf, sizeof(double) * n * correction_stride);
}

void FixBPMContacts::grow_arrays(int nmax)
{
  memory->grow(rows, nmax, memory_stride, "bpm/contacts:rows");
  // New rows hold no contacts, never stale memory.
  for (int i = nmax_rows; i < nmax; i++) rows[i][0] = 0.0;
  if (nmax > nmax_rows) nmax_rows = nmax;
}

void FixBPMContacts::set_arrays(int i)
{
  rows[i][0] = 0.0;
}

void FixBPMContacts::copy_arrays(int i, int j, int)
{
  std::memcpy(rows[j], rows[i], sizeof(double) * used(rows[i]));
}

int FixBPMContacts::pack_exchange(int i, double *buf)
{
  int n = used(rows[i]);
  std::memcpy(buf, rows[i], sizeof(double) * n);
  return n;
}

int FixBPMContacts::unpack_exchange(int nlocal, double *buf)
{
  int n = used(buf);
  std::memcpy(rows[nlocal], buf, sizeof(double) * n);
  return n;
}

int FixBPMContacts::pack_restart(int i, double *buf)
{
  int n = used(rows[i]);
  buf[0] = n + 1;    // LAMMPS convention: first value is the count including itself
  std::memcpy(buf + 1, rows[i], sizeof(double) * n);
  return n + 1;
}

void FixBPMContacts::unpack_restart(int nlocal, int nth)
{
  double **extra = atom->extra;
  int m = 0;
  for (int k = 0; k < nth; k++) m += static_cast<int>(extra[nlocal][m]);
  int n = static_cast<int>(extra[nlocal][m]) - 1;
  if (n > memory_stride)
    error->one(FLERR, "fix BPM/CONTACTS: a restart row holds more contacts than slots " + std::to_string(nslots));
  std::memcpy(rows[nlocal], &extra[nlocal][m + 1], sizeof(double) * n);
}

int FixBPMContacts::size_restart(int i)
{
  return used(rows[i]) + 1;
}

int FixBPMContacts::maxsize_restart()
{
  return memory_stride + 1;
}

double FixBPMContacts::memory_usage()
{
  return (double) atom->nmax * memory_stride * sizeof(double) +
      (double) ncorrections * correction_stride * sizeof(double);
}
