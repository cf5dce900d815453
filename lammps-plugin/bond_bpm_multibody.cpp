#include "fmt_compat.h"

#include "bond_bpm_multibody.h"
#include "fault_message.h"
#include "fix_bpm_reference.h"
#include "internal_fix.h"

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "force.h"
#include "memory.h"
#include "modify.h"
#include "neighbor.h"
#include "utils.h"

#include <cmath>
#include <string>

using namespace LAMMPS_NS;

static const char *REFERENCE_ID = "BPM_REFERENCE";

BondBPMMultibody::BondBPMMultibody(LAMMPS *lmp) :
    Bond(lmp), reference(nullptr), multibody(false), damped(false), zero_net(false)
{
  writedata = 1;
}

BondBPMMultibody::~BondBPMMultibody()
{
  if (allocated) memory->destroy(setflag);
}

void BondBPMMultibody::allocate()
{
  allocated = 1;
  int n = atom->nbondtypes;
  memory->create(setflag, n + 1, "bond:setflag");
  for (int i = 1; i <= n; i++) setflag[i] = 0;
  coeffs.assign(n, bpm_bond_coeffs{0.0, 0.0, 0.0});
}

void BondBPMMultibody::coeff(int narg, char **arg)
{
  if (narg != 4)
    error->all(FLERR, "bond_coeff for bond_style bpm/multibody takes 4 values: type k_B a_B gamma "
                      "(got " + std::to_string(narg) + ")");
  if (!allocated) allocate();
  int ilo, ihi;
  utils::bounds(FLERR, arg[0], 1, atom->nbondtypes, ilo, ihi, error);
  double k = utils::numeric(FLERR, arg[1], false, lmp);
  double a = utils::numeric(FLERR, arg[2], false, lmp);
  double gamma = utils::numeric(FLERR, arg[3], false, lmp);
  if (k < 0.0) error->all(FLERR, "bond_style bpm/multibody: k_B must be >= 0, got " + std::string(arg[1]));
  if (gamma < 0.0)
    error->all(FLERR, "bond_style bpm/multibody: gamma must be >= 0, got " + std::string(arg[3]));
  for (int i = ilo; i <= ihi; i++) {
    coeffs[i - 1] = bpm_bond_coeffs{k, a, gamma};
    setflag[i] = 1;
  }
}

void BondBPMMultibody::init_style()
{
  if (!atom->molecular) error->all(FLERR, std::string("bond_style bpm/multibody requires an atom style with bonds"));
  multibody = damped = false;
  for (auto &c : coeffs) {
    multibody = multibody || c.a != 0.0;
    damped = damped || c.gamma != 0.0;
  }
  if (damped && !comm->ghost_velocity)
    error->all(FLERR, std::string("bond_style bpm/multibody with gamma != 0 needs ghost velocities: add "
                      "'comm_modify vel yes'"));
  ensure_reference();
}

// bond_style bpm/multibody [zero_net yes|no]
void BondBPMMultibody::settings(int narg, char **arg)
{
  zero_net = false;
  bool valid = narg == 0;
  if (narg == 2 && std::string(arg[0]) == "zero_net") {
    std::string value(arg[1]);
    valid = value == "yes" || value == "no";
    zero_net = value == "yes";
  }
  if (!valid)
    error->all(FLERR, std::string("bond_style bpm/multibody takes no arguments or 'zero_net yes|no'"));
  ensure_reference();
}

// The fix exists from bond_style on, so fix_modify BPM_REFERENCE works
// before the first run; after read_restart it is created at init.
void BondBPMMultibody::ensure_reference()
{
  if (!atom->molecular) error->all(FLERR, std::string("bond_style bpm/multibody requires an atom style with bonds"));
  reference = bpm_internal_fix<FixBPMReference>(lmp, REFERENCE_ID, "BPM/REFERENCE");
}

void BondBPMMultibody::compute(int eflag, int vflag)
{
  ev_init(eflag, vflag);
  if (eflag_atom || vflag_atom)
    error->all(FLERR, std::string("bond_style bpm/multibody does not compute per-atom energy or virial"));
  int nbonds = neighbor->nbondlist;
  int nlocal = atom->nlocal;
  int nall = nlocal + atom->nghost;
  int newton_bond = force->newton_bond;
  const double *r0 = reference->bondlist_r0();
  auto bonds = reinterpret_cast<const bpm_bond_entry *>(nbonds ? neighbor->bondlist[0] : nullptr);
  const double *x = atom->x[0];
  const double *vol = nullptr, *vol0 = nullptr;
  if (multibody) {
    reference->clear_volumes(nall);
    int status = bpm_bond_volumes(x, nall, bonds, nbonds, r0, nlocal, newton_bond, reference->vol,
                                  reference->vol0);
    if (status != BPM_OK) error->one(FLERR, "bond_style bpm/multibody: volume kernel failed with status " + std::to_string(status));
    reference->communicate_volumes(newton_bond);
    vol = reference->vol;
    vol0 = reference->vol0;
  }
  bpm_tally tally{};
  bpm_fault fault{};
  int status = bpm_bond_forces(x, damped ? atom->v[0] : nullptr, nall, bonds, nbonds, r0,
                               coeffs.data(), (int64_t) coeffs.size(), vol, vol0, nlocal,
                               newton_bond, atom->f[0],
                               (eflag_global || vflag_global) ? &tally : nullptr, &fault);
  if (status == BPM_ERR_UNSTABLE)
    bpm_stop_on_fault(lmp, "bond_style bpm/multibody", fault,
                      &coeffs[neighbor->bondlist[fault.bond][2] - 1]);
  if (status != BPM_OK)
    error->one(FLERR, "bond_style bpm/multibody: force kernel failed with status " + std::to_string(status));
  if (eflag_global) energy += tally.energy;
  if (vflag_global)
    for (int k = 0; k < 6; k++) virial[k] += tally.virial[k];
  if (multibody && zero_net) apply_zero_net_correction(bonds, nbonds, r0, nall, nlocal, newton_bond);
}

// The zero-net variant's correction: per-atom multibody sums, completed on
// owners and copied to ghosts, then the correction bond by bond.
void BondBPMMultibody::apply_zero_net_correction(const bpm_bond_entry *bonds, int nbonds, const double *r0,
                                         int nall, int nlocal, int newton_bond)
{
  reference->clear_multibody_sums(nall);
  int status = bpm_multibody_sums(atom->x[0], nall, bonds, nbonds, r0, coeffs.data(),
                                  (int64_t) coeffs.size(), reference->vol, reference->vol0, nlocal,
                                  newton_bond, reference->multibody_sums);
  if (status != BPM_OK)
    error->one(FLERR, "bond_style bpm/multibody: multibody sum kernel failed with status " + std::to_string(status));
  reference->communicate_multibody_sums(newton_bond);
  bpm_tally tally{};
  status = bpm_balance_multibody(atom->x[0], nall, bonds, nbonds, reference->multibody_sums, nlocal,
                                 newton_bond, atom->f[0], vflag_global ? &tally : nullptr);
  if (status != BPM_OK)
    error->one(FLERR, "bond_style bpm/multibody: zero-net kernel failed with status " + std::to_string(status));
  if (vflag_global)
    for (int k = 0; k < 6; k++) virial[k] += tally.virial[k];
}

double BondBPMMultibody::equilibrium_distance(int)
{
  return reference && reference->max_r0() > 0.0 ? reference->max_r0() : 1.0;
}

double BondBPMMultibody::single(int type, double rsq, int i, int j, double &fforce)
{
  double r = std::sqrt(rsq);
  double r0 = reference ? reference->r0_between(i, j) : -1.0;
  if (r0 <= 0.0) r0 = reference ? reference->r0_between(j, i) : -1.0;
  fforce = 0.0;
  if (r0 <= 0.0 || r <= 0.0) return 0.0;
  // Without volumes the multibody term is left out: a dilation equal to
  // r / r0 as the kernels form it, r * (1 / r0), cancels it exactly.
  double dilation = r * (1.0 / r0);
  return bpm_bond_single(r, r0, dilation, &coeffs[type - 1], &fforce);
}

void BondBPMMultibody::write_restart(FILE *fp)
{
  fwrite(coeffs.data(), sizeof(bpm_bond_coeffs), coeffs.size(), fp);
  int flag = zero_net ? 1 : 0;
  fwrite(&flag, sizeof(int), 1, fp);
}

void BondBPMMultibody::read_restart(FILE *fp)
{
  allocate();
  int flag = 0;
  if (comm->me == 0) {
    utils::sfread(FLERR, coeffs.data(), sizeof(bpm_bond_coeffs), coeffs.size(), fp, nullptr, error);
    utils::sfread(FLERR, &flag, sizeof(int), 1, fp, nullptr, error);
  }
  MPI_Bcast(coeffs.data(), (int) (coeffs.size() * sizeof(bpm_bond_coeffs)), MPI_BYTE, 0, world);
  MPI_Bcast(&flag, 1, MPI_INT, 0, world);
  zero_net = flag != 0;
  for (int i = 1; i <= atom->nbondtypes; i++) setflag[i] = 1;
}

void BondBPMMultibody::write_data(FILE *fp)
{
  for (int i = 1; i <= atom->nbondtypes; i++)
    fprintf(fp, "%d %.17g %.17g %.17g\n", i, coeffs[i - 1].k, coeffs[i - 1].a, coeffs[i - 1].gamma);
}
