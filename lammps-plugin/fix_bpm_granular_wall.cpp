#include "fmt_compat.h"

#include "fix_bpm_granular_wall.h"

#include "comm.h"
#include "domain.h"
#include "error.h"
#include "force.h"
#include "update.h"
#include "utils.h"

#include <cstddef>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

using namespace LAMMPS_NS;

static_assert(sizeof(bpm_granular_wall) == 48 && offsetof(bpm_granular_wall, keep) == 36 &&
                  offsetof(bpm_granular_wall, material) == 40,
              "bpm_granular_wall must match the Rust RawWall layout (src/ffi/granular.rs)");

static const char *const USAGE =
    "fix ID all bpm/granular/wall number x|y|z lo|hi position velocity [keep_history] "
    "hertz/material ...";

FixBPMGranularWall::FixBPMGranularWall(LAMMPS *lmp, int narg, char **arg) :
    Fix(lmp, narg, arg), material(nullptr), fresh(1), keep_history(0), local_force(0.0),
    total_force(0.0), summed(1)
{
  if (narg < 9) error->all(FLERR, std::string("Illegal fix bpm/granular/wall command: ") + USAGE);
  if (igroup != 0)
    error->all(FLERR, std::string("fix bpm/granular/wall acts on every atom: use group all (") + USAGE + ")");
  number = utils::bnumeric(FLERR, arg[3], false, lmp);
  if (number < 1) error->all(FLERR, std::string("fix bpm/granular/wall: the number must be at least 1"));
  std::string a = arg[4], s = arg[5];
  if (a != "x" && a != "y" && a != "z")
    error->all(FLERR, "fix bpm/granular/wall: axis `" + a + "`: expected x, y or z");
  axis = a[0] - 'x';
  if (s != "lo" && s != "hi")
    error->all(FLERR, "fix bpm/granular/wall: side `" + s +
                          "`: expected lo (atoms above the plane) or hi (below)");
  side = s == "lo" ? 1 : -1;
  start = utils::numeric(FLERR, arg[6], false, lmp);
  velocity = utils::numeric(FLERR, arg[7], false, lmp);
  int first_material_word = 8;
  if (strcmp(arg[8], "keep_history") == 0) {
    keep_history = 1;
    first_material_word = 9;
  }
  std::vector<const char *> words(arg + first_material_word, arg + narg);
  char message[1024];
  material = bpm_granular_wall_material_create((int32_t) words.size(), words.data(), message,
                                               sizeof(message));
  if (!material) error->all(FLERR, std::string("fix bpm/granular/wall: ") + message);
  time_origin = update->ntimestep;
  dt_origin = update->dt;
  time_depend = 1;    // LAMMPS refuses reset_timestep while the plane moves with the step
  restart_global = 1;
  vector_flag = 1;
  size_vector = 2;
  global_freq = 1;
  extlist = new int[2]{1, 0};    // the force is extensive, the position not
  extvector = -1;
}

FixBPMGranularWall::~FixBPMGranularWall()
{
  bpm_granular_wall_material_destroy(material);
  delete[] extlist;
}

int FixBPMGranularWall::setmask()
{
  return 0;    // the pair style computes the wall's forces
}

void FixBPMGranularWall::init()
{
  if (!force->pair_match("bpm/granular", 1))
    error->all(FLERR, std::string("fix bpm/granular/wall needs pair_style bpm/granular, which computes its contacts"));
  // LAMMPS calls reset_dt() only once a run has been made: a timestep set
  // between the fix and the first run takes effect here.
  if (update->dt != dt_origin) reset_dt();
  if (domain->periodicity[axis])
    error->all(FLERR, std::string("fix bpm/granular/wall: the box is periodic along ") + "xyz"[axis] +
                          ": a wall needs a closed dimension (boundary f, s or m there)");
}

double FixBPMGranularWall::position() const
{
  return start + velocity * (double) (update->ntimestep - time_origin) * dt_origin;
}

// A new timestep: the plane goes on from where it is.
void FixBPMGranularWall::reset_dt()
{
  start = position();
  time_origin = update->ntimestep;
  dt_origin = update->dt;
}

bpm_granular_wall FixBPMGranularWall::current() const
{
  return bpm_granular_wall{number, axis, side, position(), velocity, fresh, keep_history, material};
}

void FixBPMGranularWall::set_local_force(double force)
{
  local_force = force;
  summed = 0;
}

double FixBPMGranularWall::compute_vector(int n)
{
  if (n == 1) return position();
  if (!summed) {
    MPI_Allreduce(&local_force, &total_force, 1, MPI_DOUBLE, MPI_SUM, world);
    summed = 1;
  }
  return total_force;
}

// The plane's motion as defined (not its position now), so a run resumed
// from the restart file puts the plane where the uninterrupted run does,
// to the last bit; and whether the pair style has taken the wall yet.
void FixBPMGranularWall::write_restart(FILE *fp)
{
  if (comm->me != 0) return;
  double list[] = {(double) number, (double) axis,      (double) side, start,
                   velocity,        (double) time_origin, dt_origin,     (double) fresh};
  int size = sizeof(list);
  fwrite(&size, sizeof(int), 1, fp);
  fwrite(list, sizeof(double), sizeof(list) / sizeof(double), fp);
}

// Called when this fix is defined after read_restart with the ID of one in
// the file: the wall must be the same; its plane goes on from the file.
void FixBPMGranularWall::restart(char *buf)
{
  auto list = reinterpret_cast<double *>(buf);
  if (list[0] != (double) number || list[1] != (double) axis || list[2] != (double) side ||
      list[4] != velocity) {
    auto wall = [](double n, int a, double s, double v) {
      std::ostringstream text;
      text.precision(17);
      text << "number " << (int64_t) n << ", " << "xyz"[a] << (s > 0 ? " lo" : " hi")
           << ", moving at " << v;
      return text.str();
    };
    error->all(FLERR, std::string("fix ") + id + " bpm/granular/wall: the restart file's wall is " +
                          wall(list[0], (int) list[1], list[2], list[4]) +
                          "; this command defines " + wall((double) number, axis, side, velocity) +
                          ". Define it as in the run that wrote the file, or under another fix "
                          "ID for a new wall");
  }
  start = list[3];
  time_origin = (bigint) list[5];
  dt_origin = list[6];
  fresh = (int) list[7];
}
