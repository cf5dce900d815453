#include "fmt_compat.h"

#include "fix_bpm_broken_pairs.h"

#include "atom.h"
#include "error.h"
#include "neigh_list.h"
#include "neighbor.h"

#include <string>

using namespace LAMMPS_NS;
using namespace FixConst;

FixBPMBrokenPairs::FixBPMBrokenPairs(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg)
{
  if (narg != 3) error->all(FLERR, std::string("Illegal fix BPM/BROKEN/PAIRS command: it takes no arguments"));
}

int FixBPMBrokenPairs::setmask()
{
  return PRE_EXCHANGE | PRE_FORCE | MIN_PRE_EXCHANGE | MIN_PRE_FORCE;
}

void FixBPMBrokenPairs::add(int i, int j)
{
  auto pair = std::make_pair(atom->tag[i], atom->tag[j]);
  unlisted.push_back(pair);
  unspecial.push_back(pair);
}

// Owned atom i no longer counts partner among its 1-2 neighbours.
void FixBPMBrokenPairs::forget_partner(int i, tagint partner)
{
  if (i < 0 || i >= atom->nlocal) return;
  tagint *list = atom->special[i];
  int n = atom->nspecial[i][0];
  int m = 0;
  while (m < n && list[m] != partner) m++;
  if (m == n) return;
  for (; m < n - 1; m++) list[m] = list[m + 1];
  // Only 1-2 lists exist (1-3 and 1-4 weights are 1), so all three counts agree.
  atom->nspecial[i][0] = atom->nspecial[i][1] = atom->nspecial[i][2] = n - 1;
}

void FixBPMBrokenPairs::pre_exchange()
{
  for (auto &pair : unspecial) {
    forget_partner(atom->map(pair.first), pair.second);
    forget_partner(atom->map(pair.second), pair.first);
  }
  unspecial.clear();
}

void FixBPMBrokenPairs::pre_force(int)
{
  if (unlisted.empty()) return;
  tagint *tag = atom->tag;
  int nlocal = atom->nlocal;
  const int special_bits = 3 << SBBITS;
  for (int l = 0; l < neighbor->nlist; l++) {
    NeighList *list = neighbor->lists[l];
    // A copy shares its original's rows; an occasional list holds the
    // atoms of its last build (rebuilt, with the special lists, when used).
    if (list->copy || list->occasional || !list->numneigh || !list->firstneigh) continue;
    for (auto &pair : unlisted) {
      for (int side = 0; side < 2; side++) {
        int i = atom->map(side ? pair.second : pair.first);
        tagint partner = side ? pair.first : pair.second;
        if (i < 0 || i >= nlocal) continue;
        int *row = list->firstneigh[i];
        for (int k = 0; k < list->numneigh[i]; k++)
          if (tag[row[k] & NEIGHMASK] == partner) row[k] &= ~special_bits;
      }
    }
  }
  unlisted.clear();
}
