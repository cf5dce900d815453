#include "fmt_compat.h"

#include "pair_bpm_granular.h"
#include "fix_bpm_contacts.h"
#include "internal_fix.h"
#include "fix_bpm_granular_wall.h"

#include "atom.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "fix.h"
#include "force.h"
#include "memory.h"
#include "modify.h"
#include "neigh_list.h"
#include "neighbor.h"
#include "update.h"
#include "utils.h"

#include <cmath>
#include <cstring>

using namespace LAMMPS_NS;

static const char *const CONTACTS_ID = "BPM_CONTACTS";

PairBPMGranular::PairBPMGranular(LAMMPS *lmp) :
    Pair(lmp), style(nullptr), contacts(nullptr), max_radius(0.0)
{
  restartinfo = 1;
  // compute pair bpm/granular: [1] largest correction over the radius
  // (rank 0 holds the maximum, the others 0, so the compute's sum is it),
  // [2] contacts or terms switched off (each rank counts its own atoms').
  nextra = 2;
  pvector = new double[nextra];
  pvector[0] = pvector[1] = 0.0;
  single_enable = 0;
  no_virial_fdotr_compute = 1;    // the kernel tallies the virial itself
}

PairBPMGranular::~PairBPMGranular()
{
  bpm_granular_destroy(style);
  delete[] pvector;
  if (allocated) {
    memory->destroy(setflag);
    memory->destroy(cutsq);
  }
}

void PairBPMGranular::allocate()
{
  allocated = 1;
  int n = atom->ntypes;
  memory->create(setflag, n + 1, n + 1, "pair:setflag");
  memory->create(cutsq, n + 1, n + 1, "pair:cutsq");
  for (int i = 0; i <= n; i++)
    for (int j = 0; j <= n; j++) setflag[i][j] = 0;
}

void PairBPMGranular::settings(int narg, char **)
{
  if (narg != 0) error->all(FLERR, std::string("pair_style bpm/granular takes no arguments"));
}

// One material for all spheres: the closure reads each sphere's own
// material, so coefficients per type pair would not define it.
void PairBPMGranular::coeff(int narg, char **arg)
{
  if (narg < 3 || std::string(arg[0]) != "*" || std::string(arg[1]) != "*")
    error->all(FLERR, std::string("pair_coeff for pair_style bpm/granular: 'pair_coeff * * hertz/material ...' "
                                  "(one material for every type)"));
  if (!allocated) allocate();
  words.assign(arg + 2, arg + narg);
  create_style();
  for (int i = 1; i <= atom->ntypes; i++)
    for (int j = i; j <= atom->ntypes; j++) setflag[i][j] = 1;
}

void PairBPMGranular::create_style()
{
  std::vector<const char *> ptrs;
  for (auto &w : words) ptrs.push_back(w.c_str());
  char message[1024];
  bpm_granular *created = bpm_granular_create((int32_t) ptrs.size(), ptrs.data(), message, sizeof(message));
  if (!created) error->all(FLERR, std::string("pair_coeff for pair_style bpm/granular: ") + message);
  bpm_granular_inherit_walls(created, style);
  bpm_granular_destroy(style);
  style = created;
}

// The fix exists from the first init on; a later pair_coeff may not
// change the slots it was made with.
void PairBPMGranular::ensure_contacts()
{
  int slots = (int) bpm_granular_slots(style);
  contacts = bpm_internal_fix<FixBPMContacts>(lmp, CONTACTS_ID,
                                              "BPM/CONTACTS " + std::to_string(slots));
  if (contacts->slots() != slots)
    error->all(FLERR, "pair_style bpm/granular: slots " + std::to_string(slots) +
                          " differs from the " + std::to_string(contacts->slots()) +
                          " the contact rows were made with");
}

void PairBPMGranular::init_style()
{
  if (!style) error->all(FLERR, std::string("pair_style bpm/granular: pair_coeff * * was never given"));
  if (!atom->radius_flag || !atom->rmass_flag || !atom->omega_flag || !atom->torque_flag)
    error->all(FLERR, std::string("pair_style bpm/granular needs radius, mass, omega and torque per atom: "
                                  "use atom_style sphere"));
  if (force->newton_pair)
    error->all(FLERR, std::string("pair_style bpm/granular needs newton off for pairs (each rank "
                                  "computes the pairs of its atoms and their closure): 'newton off'"));
  if (domain->dimension != 3)
    error->all(FLERR, std::string("pair_style bpm/granular is for 3-d spheres"));
  if (!atom->tag_enable)
    error->all(FLERR, std::string("pair_style bpm/granular needs atom IDs: contacts are kept by partner ID"));
  if (!comm->ghost_velocity)
    error->all(FLERR, std::string("pair_style bpm/granular needs ghost velocities: add 'comm_modify vel yes'"));
  ensure_contacts();
  // The closure counts walls as contacts; LAMMPS's own granular walls tell
  // this style nothing of theirs (fix bpm/granular/wall does).
  if (bpm_granular_has_closure(style) && comm->me == 0)
    for (int i = 0; i < modify->nfix; i++)
      if (utils::strmatch(modify->fix[i]->style, "^wall/gran"))
        error->warning(FLERR, std::string("pair_style bpm/granular: fix ") + modify->fix[i]->id +
                                  " (" + modify->fix[i]->style +
                                  ") is not a contact of the multi-contact closure: its spheres' "
                                  "corrections leave the wall's load out (use fix bpm/granular/wall)");
  double local = 0.0;
  for (int i = 0; i < atom->nlocal; i++) local = std::fmax(local, atom->radius[i]);
  MPI_Allreduce(&local, &max_radius, 1, MPI_DOUBLE, MPI_MAX, world);
  neighbor->request(this, instance_me);
}

double PairBPMGranular::init_one(int, int)
{
  return bpm_granular_cutoff(style, max_radius);
}

void PairBPMGranular::stop(const char *pass, int status, const char *message)
{
  if (status == BPM_ERR_STOPPED) error->one(FLERR, std::string("pair_style bpm/granular: ") + message);
  error->one(FLERR, std::string("pair_style bpm/granular: ") + pass + " kernel failed with status " +
                        std::to_string(status));
}

// The walls now, handed to the kernels before pass 1 (a fresh wall's
// springs restart there).
void PairBPMGranular::set_walls()
{
  // Found anew at each evaluation: `run N every M` may redefine walls
  // without an init.
  walls.clear();
  for (int i = 0; i < modify->nfix; i++)
    if (strcmp(modify->fix[i]->style, "bpm/granular/wall") == 0)
      walls.push_back(dynamic_cast<FixBPMGranularWall *>(modify->fix[i]));
  wall_state.clear();
  for (auto *w : walls) {
    if (!w) error->all(FLERR, std::string("pair_style bpm/granular: a fix bpm/granular/wall is not of this plugin"));
    wall_state.push_back(w->current());
  }
  char message[1024];
  int status = bpm_granular_set_walls(style, wall_state.data(), (int64_t) wall_state.size(),
                                      contacts->memory_rows(), atom->nlocal, message, sizeof(message));
  if (status != BPM_OK) stop("walls", status, message);
  for (auto *w : walls) w->taken();
}

void PairBPMGranular::compute(int eflag, int vflag)
{
  ev_init(eflag, vflag);
  if (eflag_atom || vflag_atom)
    error->all(FLERR, std::string("pair_style bpm/granular does not compute per-atom energy or virial"));
  int nlocal = atom->nlocal;
  int nall = nlocal + atom->nghost;
  tags.assign(atom->tag, atom->tag + nall);
  bpm_granular_atoms atoms{atom->x[0], atom->v[0], atom->omega[0], atom->radius, atom->rmass,
                           tags.data(), nall, nlocal};
  double *corrections = contacts->correction_rows(nall);
  char message[1024];
  // One image of each partner in the list: two would share a contact row.
  int status = bpm_granular_check_box(neighbor->cutneighmax, domain->h, domain->periodicity,
                                      update->ntimestep, message, sizeof(message));
  if (status != BPM_OK) stop("box", status, message);
  pvector[0] = pvector[1] = 0.0;
  set_walls();
  if (bpm_granular_has_closure(style)) {
    bpm_granular_summary summary{};
    status = bpm_granular_corrections(style, &atoms, list->inum, list->ilist, list->numneigh,
                                          list->firstneigh, contacts->memory_rows(), corrections,
                                          update->ntimestep, &summary, message, sizeof(message));
    if (status != BPM_OK) stop("corrections", status, message);
    contacts->forward_corrections();
    double largest = 0.0;
    MPI_Allreduce(&summary.largest, &largest, 1, MPI_DOUBLE, MPI_MAX, world);
    pvector[0] = comm->me == 0 ? largest : 0.0;
    pvector[1] = (double) summary.switched_off;
  }
  bpm_tally tally{};
  // A set-up (run 0, the first evaluation of a run) does not advance the
  // contact springs, as LAMMPS's own granular styles.
  // After a rebuild the memory keeps only the listed contacts.
  status = bpm_granular_forces(style, &atoms, list->inum, list->ilist, list->numneigh,
                               list->firstneigh, corrections, contacts->memory_rows(), atom->f[0],
                               atom->torque[0], update->dt, !update->setupflag,
                               neighbor->ago == 0, update->ntimestep,
                               vflag_global ? &tally : nullptr, message, sizeof(message));
  if (status != BPM_OK) stop("forces", status, message);
  wall_forces.assign(walls.size(), 0.0);
  status = bpm_granular_wall_forces(style, wall_forces.data(), (int64_t) wall_forces.size());
  if (status != BPM_OK) stop("wall forces", status, message);
  for (size_t w = 0; w < walls.size(); w++) walls[w]->set_local_force(wall_forces[w]);
  if (vflag_global)
    for (int k = 0; k < 6; k++) virial[k] += tally.virial[k];
}

void PairBPMGranular::write_restart(FILE *fp)
{
  int n = (int) words.size();
  fwrite(&n, sizeof(int), 1, fp);
  for (auto &w : words) {
    int len = (int) w.size();
    fwrite(&len, sizeof(int), 1, fp);
    fwrite(w.data(), 1, len, fp);
  }
}

void PairBPMGranular::read_restart(FILE *fp)
{
  allocate();
  int n = 0;
  if (comm->me == 0) utils::sfread(FLERR, &n, sizeof(int), 1, fp, nullptr, error);
  MPI_Bcast(&n, 1, MPI_INT, 0, world);
  words.assign(n, std::string());
  for (auto &w : words) {
    int len = 0;
    if (comm->me == 0) utils::sfread(FLERR, &len, sizeof(int), 1, fp, nullptr, error);
    MPI_Bcast(&len, 1, MPI_INT, 0, world);
    w.resize(len);
    if (comm->me == 0 && len > 0) utils::sfread(FLERR, &w[0], 1, len, fp, nullptr, error);
    MPI_Bcast(&w[0], len, MPI_CHAR, 0, world);
  }
  create_style();
  for (int i = 1; i <= atom->ntypes; i++)
    for (int j = i; j <= atom->ntypes; j++) setflag[i][j] = 1;
}
