#include "fmt_compat.h"

#include "pair_bpm_contact.h"
#include "fault_message.h"

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "force.h"
#include "memory.h"
#include "neigh_list.h"
#include "neighbor.h"
#include "utils.h"

#include <string>

using namespace LAMMPS_NS;

PairBPMContact::PairBPMContact(LAMMPS *lmp) :
    Pair(lmp), damped(false), damping_taper(false), style("pair_style bpm/contact")
{
  writedata = 1;
  restartinfo = 1;
  single_enable = 0;
  no_virial_fdotr_compute = 1;    // the kernel tallies the virial itself
}

PairBPMContact::~PairBPMContact()
{
  if (allocated) {
    memory->destroy(setflag);
    memory->destroy(cutsq);
  }
}

void PairBPMContact::allocate()
{
  allocated = 1;
  int n = atom->ntypes;
  memory->create(setflag, n + 1, n + 1, "pair:setflag");
  memory->create(cutsq, n + 1, n + 1, "pair:cutsq");
  for (int i = 0; i <= n; i++)
    for (int j = 0; j <= n; j++) setflag[i][j] = 0;
  table.assign((size_t) n * n, bpm_pair_coeffs{0.0, 0.0, 0.0, 0.0});
}

void PairBPMContact::settings(int narg, char **)
{
  if (narg != 0) error->all(FLERR, std::string("pair_style bpm/contact takes no arguments"));
}

void PairBPMContact::coeff(int narg, char **arg)
{
  if (narg != 6)
    error->all(FLERR, "pair_coeff for pair_style bpm/contact takes 6 values: I J k_P d a_P gamma "
                      "(got " + std::to_string(narg) + ")");
  double k = utils::numeric(FLERR, arg[2], false, lmp);
  double d = utils::numeric(FLERR, arg[3], false, lmp);
  double a = utils::numeric(FLERR, arg[4], false, lmp);
  double gamma = utils::numeric(FLERR, arg[5], false, lmp);
  if (k < 0.0) error->all(FLERR, "pair_style bpm/contact: k_P must be >= 0, got " + std::string(arg[2]));
  if (d <= 0.0) error->all(FLERR, "pair_style bpm/contact: d must be > 0, got " + std::string(arg[3]));
  if (a < 0.0) error->all(FLERR, "pair_style bpm/contact: a_P must be >= 0, got " + std::string(arg[4]));
  if (gamma < 0.0)
    error->all(FLERR, "pair_style bpm/contact: gamma must be >= 0, got " + std::string(arg[5]));
  set_coeffs(arg, bpm_pair_coeffs{k, d, a, gamma});
}

// The type pairs named by arg[0] and arg[1] get c.
void PairBPMContact::set_coeffs(char **arg, const bpm_pair_coeffs &c)
{
  if (!allocated) allocate();
  int ilo, ihi, jlo, jhi;
  utils::bounds(FLERR, arg[0], 1, atom->ntypes, ilo, ihi, error);
  utils::bounds(FLERR, arg[1], 1, atom->ntypes, jlo, jhi, error);
  int n = atom->ntypes;
  for (int i = ilo; i <= ihi; i++)
    for (int j = (jlo > i ? jlo : i); j <= jhi; j++) {
      table[(i - 1) * n + (j - 1)] = table[(j - 1) * n + (i - 1)] = c;
      setflag[i][j] = 1;
    }
}

void PairBPMContact::check_ghost_velocities()
{
  damped = false;
  for (auto &c : table) damped = damped || c.gamma != 0.0;
  if (damped && !comm->ghost_velocity)
    error->all(FLERR, style + " with gamma != 0 needs ghost velocities: add 'comm_modify vel yes'");
}

void PairBPMContact::init_style()
{
  if (force->special_lj[1] != 0.0)
    error->all(FLERR, std::string("pair_style bpm/contact excludes bonded pairs: use 'special_bonds lj 0 1 1'"));
  check_ghost_velocities();
  neighbor->request(this, instance_me);
}

double PairBPMContact::init_one(int i, int j)
{
  if (setflag[i][j] == 0 && setflag[j][i] == 0)
    error->all(FLERR, style + ": coefficients for types " + std::to_string(i) + " " +
                          std::to_string(j) + " were never set (no mixing)");
  setflag[i][j] = setflag[j][i] = 1;
  return table[(i - 1) * atom->ntypes + (j - 1)].d;
}

void PairBPMContact::compute(int eflag, int vflag)
{
  ev_init(eflag, vflag);
  if (eflag_atom || vflag_atom)
    error->all(FLERR, style + " does not compute per-atom energy or virial");
  int nlocal = atom->nlocal;
  int nall = nlocal + atom->nghost;
  bpm_tally tally{};
  bpm_fault fault{};
  int status = bpm_pair_forces(atom->x[0], damped ? atom->v[0] : nullptr, atom->type, nall,
                               atom->ntypes, table.data(), list->inum, list->ilist, list->numneigh,
                               list->firstneigh, force->special_lj, damping_taper ? 1 : 0, nlocal,
                               force->newton_pair,
                               atom->f[0], (eflag_global || vflag_global) ? &tally : nullptr, &fault);
  if (status == BPM_ERR_UNSTABLE) bpm_stop_on_fault(lmp, style.c_str(), fault, nullptr);
  if (status != BPM_OK) error->one(FLERR, style + ": kernel failed with status " + std::to_string(status));
  if (eflag_global) eng_vdwl += tally.energy;
  if (vflag_global)
    for (int k = 0; k < 6; k++) virial[k] += tally.virial[k];
}

void PairBPMContact::write_restart(FILE *fp)
{
  int n = atom->ntypes;
  for (int i = 1; i <= n; i++)
    for (int j = 1; j <= n; j++) fwrite(&setflag[i][j], sizeof(int), 1, fp);
  fwrite(table.data(), sizeof(bpm_pair_coeffs), table.size(), fp);
}

void PairBPMContact::read_restart(FILE *fp)
{
  allocate();
  int n = atom->ntypes;
  for (int i = 1; i <= n; i++)
    for (int j = 1; j <= n; j++) {
      if (comm->me == 0) utils::sfread(FLERR, &setflag[i][j], sizeof(int), 1, fp, nullptr, error);
      MPI_Bcast(&setflag[i][j], 1, MPI_INT, 0, world);
    }
  if (comm->me == 0)
    utils::sfread(FLERR, table.data(), sizeof(bpm_pair_coeffs), table.size(), fp, nullptr, error);
  MPI_Bcast(table.data(), (int) (table.size() * sizeof(bpm_pair_coeffs)), MPI_BYTE, 0, world);
}

void PairBPMContact::write_data(FILE *fp)
{
  int n = atom->ntypes;
  for (int i = 1; i <= n; i++) {
    auto &c = table[(i - 1) * n + (i - 1)];
    fprintf(fp, "%d %.17g %.17g %.17g %.17g\n", i, c.k, c.d, c.a, c.gamma);
  }
}

void PairBPMContact::write_data_all(FILE *fp)
{
  int n = atom->ntypes;
  for (int i = 1; i <= n; i++)
    for (int j = i; j <= n; j++) {
      auto &c = table[(i - 1) * n + (j - 1)];
      fprintf(fp, "%d %d %.17g %.17g %.17g %.17g\n", i, j, c.k, c.d, c.a, c.gamma);
    }
}
