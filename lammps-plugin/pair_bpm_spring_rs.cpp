#include "fmt_compat.h"

#include "pair_bpm_spring_rs.h"
#include "keyword_value.h"

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "neighbor.h"
#include "utils.h"

#include <cstring>
#include <string>

using namespace LAMMPS_NS;

PairBPMSpringRS::PairBPMSpringRS(LAMMPS *lmp) : PairBPMContact(lmp), anharmonic(false)
{
  damping_taper = true;
  style = "pair_style bpm/spring/rs";
}

void PairBPMSpringRS::settings(int narg, char **arg)
{
  anharmonic = false;
  for (int k = 0; k < narg; k += 2) {
    if (strcmp(arg[k], "anharmonic") != 0 || k + 1 >= narg)
      error->all(FLERR, style + " takes only the keyword 'anharmonic yes|no', got '" +
                            std::string(arg[k]) + (k + 1 < narg ? "'" : "' without a value"));
    anharmonic = bpm_yes_no(lmp, style, "anharmonic", arg[k + 1]);
  }
}

void PairBPMSpringRS::coeff(int narg, char **arg)
{
  int expected = anharmonic ? 6 : 5;
  if (narg != expected)
    error->all(FLERR, "pair_coeff for " + style + (anharmonic ? " anharmonic yes" : "") + " takes " +
                          std::to_string(expected) + " values: I J k r_c gamma" +
                          (anharmonic ? " k_a" : "") + " (got " + std::to_string(narg) + ")");
  double k = utils::numeric(FLERR, arg[2], false, lmp);
  double cut = utils::numeric(FLERR, arg[3], false, lmp);
  double gamma = utils::numeric(FLERR, arg[4], false, lmp);
  double ka = anharmonic ? utils::numeric(FLERR, arg[5], false, lmp) : 0.0;
  if (k < 0.0) error->all(FLERR, style + ": k must be >= 0, got " + std::string(arg[2]));
  if (cut <= 0.0) error->all(FLERR, style + ": r_c must be > 0, got " + std::string(arg[3]));
  if (gamma < 0.0) error->all(FLERR, style + ": gamma must be >= 0, got " + std::string(arg[4]));
  if (ka < 0.0) error->all(FLERR, style + ": k_a must be >= 0, got " + std::string(arg[5]));
  set_coeffs(arg, bpm_pair_coeffs{k, cut, ka, gamma});
}

// Upstream's pair style needs ghost velocities whatever gamma is, and
// leaves the special-bond weights to the bond style (overlay/pair).
void PairBPMSpringRS::init_style()
{
  if (!comm->ghost_velocity)
    error->all(FLERR, style + " needs ghost velocities: add 'comm_modify vel yes'");
  check_ghost_velocities();
  neighbor->request(this, instance_me);
}

void PairBPMSpringRS::write_restart(FILE *fp)
{
  int flag = anharmonic ? 1 : 0;
  fwrite(&flag, sizeof(int), 1, fp);
  PairBPMContact::write_restart(fp);
}

void PairBPMSpringRS::read_restart(FILE *fp)
{
  int flag = 0;
  if (comm->me == 0) utils::sfread(FLERR, &flag, sizeof(int), 1, fp, nullptr, error);
  MPI_Bcast(&flag, 1, MPI_INT, 0, world);
  anharmonic = flag != 0;
  PairBPMContact::read_restart(fp);
}

void PairBPMSpringRS::write_data(FILE *fp)
{
  int n = atom->ntypes;
  for (int i = 1; i <= n; i++) {
    auto &c = table[(i - 1) * n + (i - 1)];
    fprintf(fp, "%d %.17g %.17g %.17g", i, c.k, c.d, c.gamma);
    if (anharmonic) fprintf(fp, " %.17g", c.a);
    fprintf(fp, "\n");
  }
}

void PairBPMSpringRS::write_data_all(FILE *fp)
{
  int n = atom->ntypes;
  for (int i = 1; i <= n; i++)
    for (int j = i; j <= n; j++) {
      auto &c = table[(i - 1) * n + (j - 1)];
      fprintf(fp, "%d %d %.17g %.17g %.17g", i, j, c.k, c.d, c.gamma);
      if (anharmonic) fprintf(fp, " %.17g", c.a);
      fprintf(fp, "\n");
    }
}
