/* fix ID all bpm/granular/wall number axis side position velocity [keep_history] material...
 *
 * A flat wall of pair_style bpm/granular: the plane axis = position +
 * velocity t (t from the fix's definition on), its atoms on the side `lo`
 * (above the plane) or `hi` (below). The pair style computes its contacts
 * with the atoms in both of its passes, so the multi-contact closure
 * counts the wall as a contact of each atom touching it; the physics is
 * in the Rust kernels, this fix holds the wall's definition and reports
 * [1] the normal force on the wall (positive when pushed) and [2] its
 * position. Restart files keep the plane's motion: the same fix defined
 * after read_restart goes on where it was. Defined anew (as a script
 * does each stage), a wall restarts its contacts' friction springs, or
 * with `keep_history` keeps them from the wall of the same number, axis
 * and side it replaces. See
 * lammps-plugin/doc/pair_bpm_granular.md. */
#ifndef LMP_FIX_BPM_GRANULAR_WALL_H
#define LMP_FIX_BPM_GRANULAR_WALL_H

#include "fix.h"
#include "bpm_kernels.h"

namespace LAMMPS_NS {

class FixBPMGranularWall : public Fix {
 public:
  FixBPMGranularWall(class LAMMPS *, int, char **);
  ~FixBPMGranularWall() override;
  int setmask() override;
  void init() override;
  double compute_vector(int) override;
  void reset_dt() override;
  void write_restart(FILE *) override;
  void restart(char *) override;

  // The wall now; `fresh` until the pair style has taken it once.
  bpm_granular_wall current() const;
  void taken() { fresh = 0; }
  // This rank's share of the normal force on the wall, from the pair style.
  void set_local_force(double force);

 private:
  bpm_granular_wall_material *material;
  int64_t number;
  int axis, side;
  double start, velocity;
  bigint time_origin;    // the step at which the plane was at `start`
  double dt_origin;      // the timestep since then
  int fresh;
  int keep_history;    // defined anew, keeps the friction springs of the wall it replaces
  double local_force, total_force;
  int summed;
  double position() const;
};

}    // namespace LAMMPS_NS

#endif
