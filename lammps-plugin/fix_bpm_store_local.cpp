#include "fmt_compat.h"

#include "fix_bpm_store_local.h"

#include "atom.h"
#include "error.h"
#include "memory.h"
#include "update.h"
#include "utils.h"

#include <string>

using namespace LAMMPS_NS;
using namespace FixConst;

// fix ID group BPM/STORE/LOCAL N nvalues
FixBPMStoreLocal::FixBPMStoreLocal(LAMMPS *lmp, int narg, char **arg) :
    Fix(lmp, narg, arg), nreset(0), nvalues(0), nmax(0), count(0), vector(nullptr), array(nullptr)
{
  if (narg != 5) error->all(FLERR, std::string("Illegal fix BPM/STORE/LOCAL command: it takes N and nvalues"));
  nreset = utils::inumeric(FLERR, arg[3], false, lmp);
  nvalues = utils::inumeric(FLERR, arg[4], false, lmp);
  if (nreset <= 0) error->all(FLERR, "store/local: N must be > 0, got " + std::string(arg[3]));
  if (nvalues <= 0) error->all(FLERR, std::string("store/local needs at least one value to record"));
  local_flag = 1;
  local_freq = nreset;
  size_local_cols = nvalues == 1 ? 0 : nvalues;
  size_local_rows = 0;
}

FixBPMStoreLocal::~FixBPMStoreLocal()
{
  memory->destroy(vector);
  memory->destroy(array);
}

int FixBPMStoreLocal::setmask()
{
  return POST_FORCE;
}

void FixBPMStoreLocal::add(const double *row, int i, int j)
{
  int *mask = atom->mask;
  if (!(mask[i] & groupbit) || !(mask[j] & groupbit)) return;
  if (count >= nmax) {
    nmax += 1024;
    if (nvalues == 1) {
      memory->grow(vector, nmax, "bpm/store/local:vector");
      vector_local = vector;
    } else {
      memory->grow(array, nmax, nvalues, "bpm/store/local:array");
      array_local = array;
    }
  }
  for (int n = 0; n < nvalues; n++) {
    if (nvalues == 1)
      vector[count] = row[0];
    else
      array[count][n] = row[n];
  }
  count++;
}

void FixBPMStoreLocal::post_force(int)
{
  if (update->ntimestep % nreset == 0) {
    size_local_rows = count;
    count = 0;
  }
}

double FixBPMStoreLocal::memory_usage()
{
  return (double) nmax * nvalues * sizeof(double);
}
