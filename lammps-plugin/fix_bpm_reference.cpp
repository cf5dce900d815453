#include "fmt_compat.h"

#include "fix_bpm_reference.h"

#include "atom.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "memory.h"
#include "neighbor.h"
#include "update.h"

#include <cmath>
#include <cstring>
#include <string>

using namespace LAMMPS_NS;
using namespace FixConst;

FixBPMReference::FixBPMReference(LAMMPS *lmp, int narg, char **arg) :
    Fix(lmp, narg, arg), vol(nullptr), vol0(nullptr), multibody_sums(nullptr),
    owner("bond_style bpm/multibody"), r0(nullptr), ep(nullptr), with_plastic(false),
    breaking(false), restored(false), restored_breaking(false), captured(0), nmax_vol(0),
    comm_reference(true), nmax_sums(0), nmax_r0(0), slots_stale(false), list_built_at(-1), list_rebuilds(0), list_size(-1),
    max_r0_all(0.0), comm_sums(false)
{
  with_plastic = narg == 4 && strcmp(arg[3], "plastic") == 0;
  if (narg != 3 && !with_plastic)
    error->all(FLERR, std::string("Illegal fix BPM/REFERENCE command: it takes no arguments or 'plastic'"));
  if (!atom->molecular) error->all(FLERR, std::string("Fix BPM/REFERENCE requires an atom style with bonds"));
  stride = atom->bond_per_atom;
  restart_global = 1;
  restart_peratom = 1;
  create_attribute = 1;
  comm_forward = 4;    // volumes: V, V0; multibody sums: Mx, My, Mz, N
  comm_reverse = 4;
  maxexchange = (with_plastic ? 2 : 1) * stride;
  grow_arrays(atom->nmax);
  atom->add_callback(Atom::GROW);
  atom->add_callback(Atom::RESTART);
}

FixBPMReference::~FixBPMReference()
{
  atom->delete_callback(id, Atom::GROW);
  atom->delete_callback(id, Atom::RESTART);
  memory->destroy(r0);
  memory->destroy(ep);
  memory->destroy(vol);
  memory->destroy(vol0);
  memory->destroy(multibody_sums);
}

int FixBPMReference::setmask()
{
  return PRE_FORCE;
}

void FixBPMReference::setup_pre_force(int)
{
  if (stride != atom->bond_per_atom)
    error->all(FLERR, owner + ": the atoms' bond slots grew from " + std::to_string(stride) + " to " +
                          std::to_string(atom->bond_per_atom) +
                          " after the bond style was set (read_data ... extra/bond/per/atom?): "
                          "set the bond style after every command that adds bond slots");
  if (!captured) capture();
  double local = 0.0;
  for (int i = 0; i < atom->nlocal; i++)
    for (int m = 0; m < atom->num_bond[i]; m++) local = std::fmax(local, r0[i][m]);
  MPI_Allreduce(&local, &max_r0_all, 1, MPI_DOUBLE, MPI_MAX, world);
  if (max_r0_all > comm->cutghostuser && max_r0_all > neighbor->cutneighmax)
    error->all(FLERR, owner + ": a reference length (" + std::to_string(max_r0_all) +
                          ") exceeds the communication cutoff (" +
                          std::to_string(neighbor->cutneighmax) + "): use comm_modify cutoff");
  list_built_at = -1;
}

// Sets every r0 to the current bond length (first run, or after "reset").
void FixBPMReference::capture()
{
  double **x = atom->x;
  tagint **bond_atom = atom->bond_atom;
  for (int i = 0; i < atom->nlocal; i++) {
    for (int m = 0; m < atom->num_bond[i]; m++) {
      int j = atom->map(bond_atom[i][m]);
      if (j < 0)
        error->one(FLERR, owner + ": partner " + std::to_string(bond_atom[i][m]) +
                              " of atom " + std::to_string(atom->tag[i]) +
                              " is not on this rank: the bond is longer than the communication "
                              "cutoff (use comm_modify cutoff)");
      j = domain->closest_image(i, j);
      double dx = x[i][0] - x[j][0], dy = x[i][1] - x[j][1], dz = x[i][2] - x[j][2];
      r0[i][m] = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (with_plastic) ep[i][m] = 0.0;
      if (!given.empty()) {
        tagint a = atom->tag[i], b = bond_atom[i][m];
        auto it = given.find(a < b ? std::make_pair(a, b) : std::make_pair(b, a));
        if (it != given.end()) r0[i][m] = it->second;
      }
    }
  }
  given.clear();
  captured = 1;
}

// Reads "tag_i tag_j r0" lines (# comments); used at the next capture.
void FixBPMReference::read_lengths(const char *path)
{
  std::vector<double> values;
  long count = 0;
  if (comm->me == 0) {
    FILE *fp = fopen(path, "r");
    if (!fp) error->one(FLERR, std::string("fix_modify BPM_REFERENCE lengths: cannot open ") + path);
    char line[512];
    while (fgets(line, sizeof(line), fp)) {
      if (line[0] == '#' || line[0] == '\n') continue;
      double a, b, r;
      if (sscanf(line, "%lf %lf %lf", &a, &b, &r) != 3 || !(r > 0.0)) {
        fclose(fp);
        error->one(FLERR, std::string("fix_modify BPM_REFERENCE lengths: bad line in ") + path + ": " + line);
      }
      values.push_back(a);
      values.push_back(b);
      values.push_back(r);
    }
    fclose(fp);
    count = (long) values.size();
  }
  MPI_Bcast(&count, 1, MPI_LONG, 0, world);
  values.resize(count);
  MPI_Bcast(values.data(), (int) count, MPI_DOUBLE, 0, world);
  given.clear();
  for (long k = 0; k + 2 < count; k += 3) {
    tagint a = (tagint) values[k], b = (tagint) values[k + 1];
    given[a < b ? std::make_pair(a, b) : std::make_pair(b, a)] = values[k + 2];
  }
  captured = 0;
}

int FixBPMReference::modify_param(int narg, char **arg)
{
  if (strcmp(arg[0], "reset") == 0) {
    captured = 0;    // the next run's setup takes the current lengths
    restored = false;
    given.clear();
    return 1;
  }
  if (strcmp(arg[0], "lengths") == 0) {
    if (narg < 2) error->all(FLERR, std::string("fix_modify BPM_REFERENCE lengths needs a file name"));
    read_lengths(arg[1]);
    restored = false;
    return 2;
  }
  return 0;
}

const double *FixBPMReference::bondlist_r0()
{
  int n = neighbor->nbondlist;
  if (list_built_at == neighbor->lastcall && list_size == n) {
    if (slots_stale) find_slots();
    return list_r0.data();
  }
  int **bondlist = neighbor->bondlist;
  tagint *tag = atom->tag;
  list_r0.assign(n, 0.0);
  list_ep.assign(with_plastic ? n : 0, 0.0);
  find_slots();
  for (int k = 0; k < n; k++) {
    if (bondlist[k][2] <= 0) continue;
    long slot = list_slot_i[k] >= 0 ? list_slot_i[k] : list_slot_j[k];
    double value = slot >= 0 ? r0[0][slot] : -1.0;
    if (!(value > 0.0))
      error->one(FLERR, owner + ": bond " + std::to_string(tag[bondlist[k][0]]) + "-" +
                            std::to_string(tag[bondlist[k][1]]) +
                            " has no reference length (created after the reference was taken? "
                            "use fix_modify BPM_REFERENCE reset)");
    list_r0[k] = value;
    if (with_plastic) list_ep[k] = ep[0][slot];
  }
  list_built_at = neighbor->lastcall;
  list_rebuilds++;
  list_size = n;
  return list_r0.data();
}

// The slots of each listed bond in its owned atoms' rows (the bond is
// stored on one of its atoms, on both with newton_bond off), and for each
// slot the entry that uses it, so that a removed slot updates two entries
// instead of a search over the whole list.
void FixBPMReference::find_slots()
{
  int n = neighbor->nbondlist;
  int **bondlist = neighbor->bondlist;
  list_slot_i.assign(n, -1);
  list_slot_j.assign(n, -1);
  slot_entry.assign((size_t) atom->nlocal * stride, -1);
  bool unique = true;
  auto note = [&](long slot, long entry) {
    if (slot < 0) return;
    unique = unique && slot_entry[slot] < 0;
    slot_entry[slot] = entry;
  };
  for (int k = 0; k < n; k++) {
    if (bondlist[k][2] <= 0) continue;
    list_slot_i[k] = slot_of(bondlist[k][0], bondlist[k][1]);
    list_slot_j[k] = slot_of(bondlist[k][1], bondlist[k][0]);
    note(list_slot_i[k], 2L * k);
    note(list_slot_j[k], 2L * k + 1);
  }
  // A slot two entries use (a bond listed twice, as a data file may
  // hold it) falls back to a search after each removal.
  if (!unique) slot_entry.clear();
  slots_stale = false;
}

// The flat index a * stride + m of the slot of owned atom a that holds its
// bond to b, or -1. The rows of r0 and ep are one contiguous block.
long FixBPMReference::slot_of(int a, int b) const
{
  if (a >= atom->nlocal) return -1;
  for (int m = 0; m < atom->num_bond[a]; m++)
    if (atom->bond_atom[a][m] == atom->tag[b]) return (long) a * stride + m;
  return -1;
}

void FixBPMReference::store_plastic()
{
  if (!with_plastic) return;
  for (size_t k = 0; k < list_ep.size(); k++) {
    if (list_slot_i[k] >= 0) ep[0][list_slot_i[k]] = list_ep[k];
    if (list_slot_j[k] >= 0) ep[0][list_slot_j[k]] = list_ep[k];
  }
}

void FixBPMReference::remove_slot(int i, int m)
{
  int last = atom->num_bond[i] - 1;
  r0[i][m] = r0[i][last];
  r0[i][last] = 0.0;
  if (with_plastic) {
    ep[i][m] = ep[i][last];
    ep[i][last] = 0.0;
  }
  bool mapped = !slots_stale && !slot_entry.empty() && list_built_at == neighbor->lastcall &&
      slot_entry.size() == (size_t) atom->nlocal * stride;
  if (!mapped) {
    slots_stale = true;
    return;
  }
  auto entry_slot = [&](long entry) -> long & {
    return (entry & 1) ? list_slot_j[entry >> 1] : list_slot_i[entry >> 1];
  };
  long gone = (long) i * stride + m, moved = (long) i * stride + last;
  if (slot_entry[gone] >= 0) entry_slot(slot_entry[gone]) = -1;
  slot_entry[gone] = -1;
  if (moved != gone) {
    long entry = slot_entry[moved];
    if (entry >= 0) entry_slot(entry) = gone;
    slot_entry[gone] = entry;
    slot_entry[moved] = -1;
  }
}

bool FixBPMReference::bond_values(int i, int j, double &r0_value, double &ep_value)
{
  long slot = slot_of(i, j);
  if (slot < 0) slot = slot_of(j, i);
  if (slot < 0) return false;
  r0_value = r0[0][slot];
  ep_value = with_plastic ? ep[0][slot] : 0.0;
  return true;
}

double FixBPMReference::r0_between(int i, int j)
{
  long slot = slot_of(i, j);
  if (slot < 0) slot = slot_of(j, i);
  return slot >= 0 ? r0[0][slot] : -1.0;
}

void FixBPMReference::ensure_volumes(int nall)
{
  if (nall > nmax_vol) {
    nmax_vol = atom->nmax > nall ? atom->nmax : nall;
    memory->destroy(vol);
    memory->destroy(vol0);
    memory->create(vol, nmax_vol, "bpm/reference:vol");
    memory->create(vol0, nmax_vol, "bpm/reference:vol0");
  }
}

void FixBPMReference::clear_volumes(int nall)
{
  ensure_volumes(nall);
  for (int i = 0; i < nall; i++) vol[i] = vol0[i] = 0.0;
}

void FixBPMReference::clear_multibody_sums(int nall)
{
  if (nall > nmax_sums) {
    nmax_sums = atom->nmax > nall ? atom->nmax : nall;
    memory->destroy(multibody_sums);
    memory->create(multibody_sums, 4 * nmax_sums, "bpm/reference:multibody_sums");
  }
  for (int i = 0; i < 4 * nall; i++) multibody_sums[i] = 0.0;
}

void FixBPMReference::communicate_multibody_sums(int newton_bond)
{
  comm_sums = true;
  communicate(newton_bond);
  comm_sums = false;
}

void FixBPMReference::communicate_volumes(int newton_bond, bool with_reference)
{
  comm_reference = with_reference;
  communicate(newton_bond);
  comm_reference = true;
}

void FixBPMReference::communicate(int newton_bond)
{
#if defined(BPM_MODERN_LAMMPS)    // 2022 and later: comm calls overloaded by class
  if (newton_bond) comm->reverse_comm(this);
  comm->forward_comm(this);
#else
  if (newton_bond) comm->reverse_comm_fix(this);
  comm->forward_comm_fix(this);
#endif
}

int FixBPMReference::pack_forward_comm(int n, int *list, double *buf, int, int *)
{
  int m = 0;
  if (comm_sums) {
    for (int k = 0; k < n; k++)
      for (int c = 0; c < 4; c++) buf[m++] = multibody_sums[4 * list[k] + c];
    return m;
  }
  for (int k = 0; k < n; k++) {
    buf[m++] = vol[list[k]];
    if (comm_reference) buf[m++] = vol0[list[k]];
  }
  return m;
}

void FixBPMReference::unpack_forward_comm(int n, int first, double *buf)
{
  int m = 0;
  if (comm_sums) {
    for (int i = first; i < first + n; i++)
      for (int c = 0; c < 4; c++) multibody_sums[4 * i + c] = buf[m++];
    return;
  }
  for (int i = first; i < first + n; i++) {
    vol[i] = buf[m++];
    if (comm_reference) vol0[i] = buf[m++];
  }
}

int FixBPMReference::pack_reverse_comm(int n, int first, double *buf)
{
  int m = 0;
  if (comm_sums) {
    for (int i = first; i < first + n; i++)
      for (int c = 0; c < 4; c++) buf[m++] = multibody_sums[4 * i + c];
    return m;
  }
  for (int i = first; i < first + n; i++) {
    buf[m++] = vol[i];
    if (comm_reference) buf[m++] = vol0[i];
  }
  return m;
}

void FixBPMReference::unpack_reverse_comm(int n, int *list, double *buf)
{
  int m = 0;
  if (comm_sums) {
    for (int k = 0; k < n; k++)
      for (int c = 0; c < 4; c++) multibody_sums[4 * list[k] + c] += buf[m++];
    return;
  }
  for (int k = 0; k < n; k++) {
    vol[list[k]] += buf[m++];
    if (comm_reference) vol0[list[k]] += buf[m++];
  }
}

void FixBPMReference::grow_arrays(int nmax)
{
  // New rows start at 0 ("no reference length"), never at stale memory.
  memory->grow(r0, nmax, stride, "bpm/reference:r0");
  if (with_plastic) memory->grow(ep, nmax, stride, "bpm/reference:ep");
  for (int i = nmax_r0; i < nmax; i++)
    for (int m = 0; m < stride; m++) {
      r0[i][m] = 0.0;
      if (with_plastic) ep[i][m] = 0.0;
    }
  if (nmax > nmax_r0) nmax_r0 = nmax;
}

void FixBPMReference::copy_arrays(int i, int j, int)
{
  for (int m = 0; m < stride; m++) {
    r0[j][m] = r0[i][m];
    if (with_plastic) ep[j][m] = ep[i][m];
  }
}

// Per atom: r0 of its bonds, then (plastic) their e_p.
int FixBPMReference::pack_exchange(int i, double *buf)
{
  int n = atom->num_bond[i];
  for (int m = 0; m < n; m++) buf[m] = r0[i][m];
  if (!with_plastic) return n;
  for (int m = 0; m < n; m++) buf[n + m] = ep[i][m];
  return 2 * n;
}

int FixBPMReference::unpack_exchange(int nlocal, double *buf)
{
  int n = atom->num_bond[nlocal];
  for (int m = 0; m < stride; m++) {
    r0[nlocal][m] = m < n ? buf[m] : 0.0;
    if (with_plastic) ep[nlocal][m] = m < n ? buf[n + m] : 0.0;
  }
  return with_plastic ? 2 * n : n;
}

int FixBPMReference::pack_restart(int i, double *buf)
{
  int n = pack_exchange(i, buf + 1);
  buf[0] = n + 1;    // LAMMPS convention: first value is the count including itself
  return n + 1;
}

// A file written without e_p (elastic styles) leaves them at 0.
void FixBPMReference::unpack_restart(int nlocal, int nth)
{
  double **extra = atom->extra;
  int m = 0;
  for (int k = 0; k < nth; k++) m += static_cast<int>(extra[nlocal][m]);
  int count = static_cast<int>(extra[nlocal][m]) - 1;
  int n = atom->num_bond[nlocal];
  bool has_plastic = count == 2 * n && n > 0;
  for (int b = 0; b < stride; b++) {
    r0[nlocal][b] = b < n && b < count ? extra[nlocal][m + 1 + b] : 0.0;
    if (with_plastic) ep[nlocal][b] = b < n && has_plastic ? extra[nlocal][m + 1 + n + b] : 0.0;
  }
}

int FixBPMReference::size_restart(int i)
{
  return (with_plastic ? 2 : 1) * atom->num_bond[i] + 1;
}

int FixBPMReference::maxsize_restart()
{
  return (with_plastic ? 2 : 1) * stride + 1;
}

// One double: captured + 2 breaking (files of older versions hold 0 or 1).
void FixBPMReference::write_restart(FILE *fp)
{
  if (comm->me == 0) {
    int size = sizeof(double);
    double flag = captured + (breaking ? 2 : 0);
    fwrite(&size, sizeof(int), 1, fp);
    fwrite(&flag, sizeof(double), 1, fp);
  }
}

void FixBPMReference::restart(char *buf)
{
  int flag = static_cast<int>(reinterpret_cast<double *>(buf)[0]);
  captured = flag & 1;
  restored = true;
  restored_breaking = (flag & 2) != 0;
}

double FixBPMReference::memory_usage()
{
  return (with_plastic ? 2.0 : 1.0) * atom->nmax * stride * sizeof(double) +
         2.0 * nmax_vol * sizeof(double) + 4.0 * nmax_sums * sizeof(double) +
         (double) (list_r0.capacity() + list_ep.capacity()) * sizeof(double) +
         (double) (list_slot_i.capacity() + list_slot_j.capacity() + slot_entry.capacity()) *
             sizeof(long);
}
