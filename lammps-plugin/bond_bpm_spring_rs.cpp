#include "fmt_compat.h"

#include "bond_bpm_spring_rs.h"
#include "fault_message.h"
#include "fix_bpm_broken_pairs.h"
#include "fix_bpm_reference.h"
#include "fix_bpm_store_local.h"
#include "internal_fix.h"
#include "keyword_value.h"

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "force.h"
#include "memory.h"
#include "modify.h"
#include "neighbor.h"
#include "update.h"
#include "utils.h"

#include <cmath>
#include <cstring>
#include <string>

using namespace LAMMPS_NS;

static const char *REFERENCE_ID = "BPM_REFERENCE";
static const char *BROKEN_PAIRS_ID = "BPM_BROKEN_PAIRS";

BondBPMSpringRS::BondBPMSpringRS(LAMMPS *lmp, bool plastic_bonds) :
    Bond(lmp), plastic(plastic_bonds),
    style(plastic_bonds ? "bond_style bpm/spring/plastic/rs" : "bond_style bpm/spring/rs"),
    break_flag(1), smooth(1), normalize(0), volume(0), overlay(0), damped(false), live(true),
    store_every(0), rows(bpm_list_rows_create()), list_edits(0), reference(nullptr),
    broken_pairs(nullptr), store(nullptr)
{
  writedata = 1;
}

BondBPMSpringRS::~BondBPMSpringRS()
{
  bpm_list_rows_destroy(rows);
  if (allocated) memory->destroy(setflag);
}

void BondBPMSpringRS::allocate()
{
  allocated = 1;
  int n = atom->nbondtypes;
  memory->create(setflag, n + 1, "bond:setflag");
  for (int i = 1; i <= n; i++) setflag[i] = 0;
  coeffs.assign(n, bpm_bond_coeffs{0.0, 0.0, 0.0});
  rules.assign(n, bpm_bond_failure{1.0, 0.0, 1, 1, 0, 0});
  with_volume.assign(n, 0);
}

// Upstream's keywords, in any order; store/local takes every value word
// that follows it.
void BondBPMSpringRS::settings(int narg, char **arg)
{
  break_flag = smooth = 1;
  normalize = volume = overlay = 0;
  store_id.clear();
  store_values.clear();
  int k = 0;
  while (k < narg) {
    std::string word = arg[k];
    if (word == "store/local") {
      if (k + 2 >= narg) error->all(FLERR, style + ": store/local needs a fix ID, N and values");
      store_id = arg[k + 1];
      store_every = utils::inumeric(FLERR, arg[k + 2], false, lmp);
      k += 3;
      for (; k < narg; k++) {
        std::string value = arg[k];
        if (value == "id1" || value == "id2" || value == "time" || value == "x" || value == "y" ||
            value == "z")
          store_values.push_back(value);
        else if (value == "x/ref" || value == "y/ref" || value == "z/ref")
          error->all(FLERR, style + ": store/local value " + value +
                                " (reference positions) is not supported; use x, y, z");
        else
          break;
      }
      if (store_values.empty())
        error->all(FLERR, style + ": store/local needs at least one value (id1 id2 time x y z)");
      continue;
    }
    if (k + 1 >= narg) error->all(FLERR, style + ": keyword " + word + " needs yes or no");
    int *flag = word == "break"           ? &break_flag
                : word == "smooth"        ? &smooth
                : word == "normalize"     ? &normalize
                : word == "volume/factor" ? &volume
                : word == "overlay/pair"  ? &overlay
                                          : nullptr;
    if (!flag)
      error->all(FLERR, style + ": unknown keyword '" + word +
                            "' (break, smooth, normalize, volume/factor, overlay/pair, store/local)");
    *flag = bpm_yes_no(lmp, style, word, arg[k + 1]) ? 1 : 0;
    k += 2;
  }
  if (smooth && !break_flag)
    error->all(FLERR, style + ": smooth yes needs break yes: with break no, add 'smooth no' "
                              "(past epsilon_c the smoothing factor turns negative and the force "
                              "would reverse)");
  apply_flags();
  ensure_fixes();
}

// The keywords into every type's rule.
void BondBPMSpringRS::apply_flags()
{
  for (auto &r : rules) {
    r.breaks = break_flag;
    r.smooth = smooth;
    r.normalize = normalize;
    r.yields = plastic ? 1 : 0;
  }
}

void BondBPMSpringRS::coeff(int narg, char **arg)
{
  int expected = 4 + (plastic ? 1 : 0) + (volume ? 1 : 0);
  if (narg != expected)
    error->all(FLERR, "bond_coeff for " + style + (volume ? " volume/factor yes" : "") + " takes " +
                          std::to_string(expected) + " values: type k epsilon_c gamma" +
                          (plastic ? " epsilon_p" : "") + (volume ? " a_v" : "") + " (got " +
                          std::to_string(narg) + ")");
  if (!allocated) allocate();
  int ilo, ihi;
  utils::bounds(FLERR, arg[0], 1, atom->nbondtypes, ilo, ihi, error);
  double k = utils::numeric(FLERR, arg[1], false, lmp);
  double critical = utils::numeric(FLERR, arg[2], false, lmp);
  double gamma = utils::numeric(FLERR, arg[3], false, lmp);
  double yield = plastic ? utils::numeric(FLERR, arg[4], false, lmp) : 0.0;
  double a = volume ? utils::numeric(FLERR, arg[expected - 1], false, lmp) : 0.0;
  if (k < 0.0) error->all(FLERR, style + ": k must be >= 0, got " + std::string(arg[1]));
  if (gamma < 0.0) error->all(FLERR, style + ": gamma must be >= 0, got " + std::string(arg[3]));
  bpm_bond_failure rule{critical, yield, break_flag, smooth, normalize, plastic ? 1 : 0};
  char why[512];
  if (bpm_check_bond_failure(&rule, why, sizeof(why)) != BPM_OK)
    error->all(FLERR, "bond_coeff " + std::string(arg[0]) + " for " + style + ": " + why);
  for (int i = ilo; i <= ihi; i++) {
    coeffs[i - 1] = bpm_bond_coeffs{k, a, gamma};
    rules[i - 1] = rule;
    with_volume[i - 1] = volume;
    setflag[i] = 1;
  }
}

// The fixes exist from bond_style on, so fix_modify BPM_REFERENCE works
// before the first run; after read_restart they are made at init.
void BondBPMSpringRS::ensure_fixes()
{
  if (!atom->molecular) error->all(FLERR, style + " requires an atom style with bonds");
  reference = bpm_internal_fix<FixBPMReference>(
      lmp, REFERENCE_ID, std::string("BPM/REFERENCE") + (plastic ? " plastic" : ""));
  if (plastic && !reference->plastic())
    error->all(FLERR, style + ": the bonds' reference lengths are kept by an elastic bond style's "
                              "fix (no plastic strains): the deck's first bond_style must be the "
                              "plastic one, or 'unfix BPM_REFERENCE' first");
  reference->owner = style;

  broken_pairs = nullptr;
  if (break_flag)
    broken_pairs = bpm_internal_fix<FixBPMBrokenPairs>(lmp, BROKEN_PAIRS_ID, "BPM/BROKEN/PAIRS");

  store = nullptr;
  if (!store_id.empty()) {
    store = bpm_internal_fix<FixBPMStoreLocal>(
        lmp, store_id,
        "BPM/STORE/LOCAL " + std::to_string(store_every) + " " + std::to_string(store_values.size()));
    if (store->values() != (int) store_values.size() || store->every() != store_every)
      error->all(FLERR, style + ": store/local fix ID " + store_id +
                            " holds another N or other values (a store/local of an earlier "
                            "bond_style?): give it another ID");
  }
}

void BondBPMSpringRS::init_style()
{
  ensure_fixes();
  if (!comm->ghost_velocity)
    error->all(FLERR, style + " needs ghost velocities: add 'comm_modify vel yes'");
  if (force->angle || force->dihedral || force->improper)
    error->all(FLERR, style + " cannot be used with angle, dihedral or improper styles");
  check_special_weights();
  if (break_flag && reference->restored_unbreakable())
    error->all(FLERR, style + " with break yes reads a restart file written with bonds that do "
                              "not break (break no, or bond_style bpm/multibody): bonds past "
                              "epsilon_c would all break at the first step. Continue with "
                              "break no, or start the breaking run from a data file");
  reference->set_breaking(break_flag != 0);
  // A later bond_style can change the flags under coefficients checked
  // with the old ones: each type is checked again as it now stands.
  char why[512];
  for (int i = 1; i <= atom->nbondtypes; i++) {
    if (!setflag[i]) continue;
    if (bpm_check_bond_failure(&rules[i - 1], why, sizeof(why)) != BPM_OK)
      error->all(FLERR, style + ": bond type " + std::to_string(i) + ": " + why);
    if (volume && !with_volume[i - 1])
      error->all(FLERR, style + ": bond type " + std::to_string(i) +
                            " has no a_v: give its bond_coeff after 'volume/factor yes'");
  }
  damped = false;
  live = break_flag || plastic || normalize;
  for (auto &c : coeffs) damped = damped || c.gamma != 0.0;
  for (int i = 1; i <= atom->nbondtypes; i++)
    if (!setflag[i]) error->all(FLERR, style + ": bond type " + std::to_string(i) + " has no bond_coeff");
}

// Upstream's rules: bonded pairs either feel the pair style too
// (overlay/pair yes: every weight 1) or not (lj 0 1 1), and only 1-2
// special lists may exist, so that a broken bond's pair can be restored.
void BondBPMSpringRS::check_special_weights()
{
  double *lj = force->special_lj, *coul = force->special_coul;
  auto weights = [&]() {
    return "lj " + std::to_string(lj[1]) + " " + std::to_string(lj[2]) + " " + std::to_string(lj[3]) +
           ", coul " + std::to_string(coul[1]) + " " + std::to_string(coul[2]) + " " +
           std::to_string(coul[3]);
  };
  if (lj[2] != 1.0 || lj[3] != 1.0 || coul[2] != 1.0 || coul[3] != 1.0)
    error->all(FLERR, style + " needs 1-3 and 1-4 special weights of 1 (got " + weights() +
                          "): use 'special_bonds lj 0 1 1 coul 1 1 1'");
  if (overlay) {
    if (lj[1] != 1.0 || coul[1] != 1.0)
      error->all(FLERR, style + " with overlay/pair yes needs every special weight 1, so that "
                                "bonded pairs feel the pair style too (got " + weights() +
                                "): use 'special_bonds lj/coul 1 1 1'");
    return;
  }
  if (lj[1] != 0.0)
    error->all(FLERR, style + " with overlay/pair no needs special lj weights 0 1 1, so that "
                              "bonded pairs do not feel the pair style (got " + weights() +
                              "): use 'special_bonds lj 0 1 1 coul 1 1 1'");
  if (break_flag && coul[1] != 1.0)
    error->all(FLERR, style + " with break yes needs special coul weights 1 1 1, so that bonded "
                              "pairs stay in the neighbour lists to become contacts (got " +
                              weights() + "): use 'special_bonds lj 0 1 1 coul 1 1 1'");
  if (break_flag && force->newton_bond)
    error->all(FLERR, style + " with break yes and overlay/pair no needs newton_bond off, so that "
                              "each rank sees the breaks of its atoms' bonds: use 'newton on off'");
}

void BondBPMSpringRS::compute(int eflag, int vflag)
{
  ev_init(eflag, vflag);
  if (eflag_atom || vflag_atom)
    error->all(FLERR, style + " does not compute per-atom energy or virial");
  int nbonds = neighbor->nbondlist;
  int nlocal = atom->nlocal;
  int nall = nlocal + atom->nghost;
  int newton_bond = force->newton_bond;
  const double *r0 = reference->bondlist_r0();
  double *plastic_strains = plastic ? reference->bondlist_plastic() : nullptr;
  auto bonds = reinterpret_cast<bpm_bond_entry *>(nbonds ? neighbor->bondlist[0] : nullptr);
  const double *x = atom->x[0];
  const double *vol = nullptr, *vol0 = nullptr;
  bool tallied = eflag_global || vflag_global;
  if (live && coeffs.size() == 1 && !tallied) {
    bpm_fault fault{};
    int status = BPM_OK;
    bpm_failure_counts found =
        compute_rows(bonds, r0, plastic_strains, newton_bond ? nall : nlocal, fault, status);
    if (status == BPM_ERR_UNSTABLE)
      bpm_stop_on_fault(lmp, style.c_str(), fault, &coeffs[0]);
    if (status == BPM_ERR_STALE)
      error->one(FLERR, style + ": the bond rows are out of step with the bond list (a bug: "
                                "please report)");
    if (status != BPM_OK)
      error->one(FLERR, style + ": row kernels failed with status " + std::to_string(status));
    settle_failures(found);
    return;
  }
  if (volume) {
    reference->clear_volumes(nall);
    int status = bpm_intact_bond_volumes(x, nall, bonds, nbonds, r0, plastic_strains, nlocal,
                                         newton_bond, reference->vol, reference->vol0);
    if (status != BPM_OK)
      error->one(FLERR, style + ": volume kernel failed with status " + std::to_string(status));
    reference->communicate_volumes(newton_bond);
    vol = reference->vol;
    vol0 = reference->vol0;
  }
  bpm_tally tally{};
  bpm_fault fault{};
  bpm_tally *sums = (eflag_global || vflag_global) ? &tally : nullptr;
  const double *v = damped ? atom->v[0] : nullptr;
  int status;
  bpm_failure_counts found{0, 0};
  if (live) {
    broken.resize(nbonds > 0 ? nbonds : 1);
    // Upstream's plastic style lets no bond break while a run is set up
    // (its source gates breaks on update->setupflag); its elastic style
    // has no such gate, so neither has ours. A bond past epsilon_c in
    // such a set-up gets a negative smoothing factor, as upstream's does.
    int may_break = plastic ? !update->setupflag : 1;
    status = bpm_failing_bond_forces(x, v, nall, bonds, nbonds, r0, plastic_strains, coeffs.data(),
                                     rules.data(), (int64_t) coeffs.size(), may_break, vol, vol0,
                                     nlocal, newton_bond, atom->f[0], broken.data(), &found, sums,
                                     &fault);
  } else {
    status = bpm_bond_forces(x, v, nall, bonds, nbonds, r0, coeffs.data(), (int64_t) coeffs.size(),
                             vol, vol0, nlocal, newton_bond, atom->f[0], sums, &fault);
  }
  if (status == BPM_ERR_UNSTABLE)
    bpm_stop_on_fault(lmp, style.c_str(), fault, &coeffs[neighbor->bondlist[fault.bond][2] - 1]);
  if (status != BPM_OK)
    error->one(FLERR, style + ": force kernel failed with status " + std::to_string(status));
  settle_failures(found);
  // The list kernel changed the list or its plastic strains behind the rows.
  if (found.broken > 0 || found.yielded > 0) list_edits++;
  if (eflag_global) energy += tally.energy;
  if (vflag_global)
    for (int k = 0; k < 6; k++) virial[k] += tally.virial[k];
}

// After a pass: plastic strains kept per atom, broken bonds (their list
// indices lead `broken`) processed.
void BondBPMSpringRS::settle_failures(const bpm_failure_counts &found)
{
  if (found.yielded > 0) reference->store_plastic();
  for (int64_t k = 0; k < found.broken; k++) {
    int n = broken[k];
    process_broken(neighbor->bondlist[n][0], neighbor->bondlist[n][1]);
  }
}

// The rows' pass: rows synced with the list (built anew only after a
// neighbour build or a list-kernel step), the volumes V every step and
// V0 only when bonds broke or yielded, then the forces on atoms
// 0..ngather. The same forces, breaks and plastic strains as the list
// kernel, bit for bit.
bpm_failure_counts BondBPMSpringRS::compute_rows(bpm_bond_entry *bonds, const double *r0,
                                                 double *plastic_strains, int ngather,
                                                 bpm_fault &fault, int &status)
{
  int nbonds = neighbor->nbondlist;
  int nall = atom->nlocal + atom->nghost;
  const double *x = atom->x[0];
  bpm_failure_counts found{0, 0};
  int stale = 0;
  // The rows follow the reference fix's list-aligned lengths (rebuilt at
  // each neighbour build and run set-up) and the list kernel's edits.
  status = bpm_list_rows_sync(rows, (int64_t) reference->list_builds(), (int64_t) list_edits,
                              bonds, nbonds, r0, plastic_strains, nall, &stale);
  if (status != BPM_OK) return found;
  const double *vol = nullptr;
  if (volume) {
    // Every rank sums and sends V0 if one must: the communication packs
    // V0 with V on all ranks or none, and a break on one rank changes the
    // V0 of another's ghosts.
    int stale_here = stale;
    MPI_Allreduce(&stale_here, &stale, 1, MPI_INT, MPI_MAX, world);
    reference->ensure_volumes(nall);
    status = bpm_list_rows_volumes(rows, x, nall, ngather, force->newton_bond, reference->vol,
                                   stale ? reference->vol0 : nullptr);
    if (status != BPM_OK) return found;
    reference->communicate_volumes(force->newton_bond, stale != 0);
    if (stale) {
      status = bpm_list_rows_set_reference(rows, reference->vol0, nall);
      if (status != BPM_OK) return found;
    }
    vol = reference->vol;
  }
  broken.resize(nbonds > 0 ? nbonds : 1);
  int may_break = plastic ? !update->setupflag : 1;
  const double *v = damped ? atom->v[0] : nullptr;
  status = bpm_list_rows_forces(rows, x, v, nall, &coeffs[0], &rules[0], may_break, vol, ngather,
                                atom->f[0], bonds, nbonds, plastic_strains, broken.data(), &found,
                                &fault);
  return found;
}

// A bond that broke: recorded, its pair handed to the contact, and gone
// from its owned atoms' bond arrays.
void BondBPMSpringRS::process_broken(int i, int j)
{
  if (store) {
    std::vector<double> &row = store_row;
    row.resize(store_values.size());
    double **x = atom->x;
    for (size_t n = 0; n < store_values.size(); n++) {
      const std::string &value = store_values[n];
      row[n] = value == "id1"    ? (double) atom->tag[i]
               : value == "id2"  ? (double) atom->tag[j]
               : value == "time" ? (double) update->ntimestep
               : value == "x"    ? 0.5 * (x[i][0] + x[j][0])
               : value == "y"    ? 0.5 * (x[i][1] + x[j][1])
                                 : 0.5 * (x[i][2] + x[j][2]);
    }
    store->add(row.data(), i, j);
  }
  if (broken_pairs && !overlay) broken_pairs->add(i, j);
  forget_bond(i, j);
  forget_bond(j, i);
}

// Owned atom i drops its bond to j: its last bond takes the slot.
void BondBPMSpringRS::forget_bond(int i, int j)
{
  if (i >= atom->nlocal) return;
  int *num_bond = atom->num_bond;
  for (int m = 0; m < num_bond[i]; m++) {
    if (atom->bond_atom[i][m] != atom->tag[j]) continue;
    int last = num_bond[i] - 1;
    reference->remove_slot(i, m);
    atom->bond_type[i][m] = atom->bond_type[i][last];
    atom->bond_atom[i][m] = atom->bond_atom[i][last];
    num_bond[i]--;
    return;
  }
}

double BondBPMSpringRS::equilibrium_distance(int)
{
  double stretch = 1.0;
  for (auto &r : rules) stretch = std::fmax(stretch, 1.0 + r.critical_strain);
  return reference && reference->max_r0() > 0.0 ? reference->max_r0() * stretch : 1.0;
}

double BondBPMSpringRS::single(int type, double rsq, int i, int j, double &fforce)
{
  fforce = 0.0;
  if (type <= 0 || !reference) return 0.0;
  double r0 = 0.0, e_p = 0.0;
  if (!reference->bond_values(i, j, r0, e_p)) return 0.0;
  return bpm_failing_bond_single(std::sqrt(rsq), r0, e_p, &coeffs[type - 1], &rules[type - 1],
                                 &fforce);
}

void BondBPMSpringRS::write_restart(FILE *fp)
{
  int flags[6] = {break_flag, smooth, normalize, volume, overlay, plastic ? 1 : 0};
  fwrite(flags, sizeof(int), 6, fp);
  fwrite(coeffs.data(), sizeof(bpm_bond_coeffs), coeffs.size(), fp);
  fwrite(rules.data(), sizeof(bpm_bond_failure), rules.size(), fp);
}

void BondBPMSpringRS::read_restart(FILE *fp)
{
  allocate();
  int flags[6] = {0, 0, 0, 0, 0, 0};
  if (comm->me == 0) {
    utils::sfread(FLERR, flags, sizeof(int), 6, fp, nullptr, error);
    utils::sfread(FLERR, coeffs.data(), sizeof(bpm_bond_coeffs), coeffs.size(), fp, nullptr, error);
    utils::sfread(FLERR, rules.data(), sizeof(bpm_bond_failure), rules.size(), fp, nullptr, error);
  }
  MPI_Bcast(flags, 6, MPI_INT, 0, world);
  MPI_Bcast(coeffs.data(), (int) (coeffs.size() * sizeof(bpm_bond_coeffs)), MPI_BYTE, 0, world);
  MPI_Bcast(rules.data(), (int) (rules.size() * sizeof(bpm_bond_failure)), MPI_BYTE, 0, world);
  if ((flags[5] != 0) != plastic)
    error->all(FLERR, style + ": the restart file holds another bond style's coefficients");
  break_flag = flags[0];
  smooth = flags[1];
  normalize = flags[2];
  volume = flags[3];
  overlay = flags[4];
  with_volume.assign(atom->nbondtypes, volume);
  for (int i = 1; i <= atom->nbondtypes; i++) setflag[i] = 1;
}

void BondBPMSpringRS::write_data(FILE *fp)
{
  for (int i = 1; i <= atom->nbondtypes; i++) {
    auto &c = coeffs[i - 1];
    auto &r = rules[i - 1];
    fprintf(fp, "%d %.17g %.17g %.17g", i, c.k, r.critical_strain, c.gamma);
    if (plastic) fprintf(fp, " %.17g", r.plastic_strain);
    if (volume) fprintf(fp, " %.17g", c.a);
    fprintf(fp, "\n");
  }
}
