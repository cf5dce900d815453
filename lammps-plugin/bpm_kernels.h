/* C ABI of the Rust kernels (src/ffi.rs). The only interface between the
 * LAMMPS shim and the physics: the shim passes whole lists, never one
 * interaction at a time. Every function returns a BPM_* status. */
#ifndef BPM_KERNELS_H
#define BPM_KERNELS_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

enum {
  BPM_OK = 0,        /* success */
  BPM_ERR_NULL = 1,  /* a required pointer was null or a count negative */
  BPM_ERR_INDEX = 2, /* an atom index outside 0..nall */
  BPM_ERR_TYPE = 3,  /* a bond or atom type without coefficients */
  BPM_ERR_PANIC = 4, /* internal error in the kernels (a bug) */
  BPM_ERR_UNSTABLE = 5, /* forces computed, but an interaction left the model's range (fault) */
  BPM_ERR_STOPPED = 6,  /* a pass stopped; the message written says why */
  BPM_ERR_STALE = 7     /* list rows used with another list, or without their V0 set */
};

/* Kinds of fault: the first sign of a blow-up, caught while values are finite. */
enum {
  BPM_FAULT_NON_FINITE = 1,         /* a NaN or infinite position, velocity or force */
  BPM_FAULT_BOND_COLLAPSED = 2,     /* bond shorter than 0.2 r0 */
  BPM_FAULT_BOND_OVERSTRETCHED = 3  /* bond longer than 3 r0 */
};

/* The first faulty interaction of a call: kind, local atom indices, distance,
 * reference length (bond) or contact distance (pair), bonded or not, and the
 * bond's row in the bond list (-1 for a pair). */
typedef struct {
  int32_t kind;
  int64_t i, j;
  double r, reference;
  uint8_t bonded;
  int64_t bond;
} bpm_fault;

/* One bond: the layout of a row of LAMMPS's neighbor->bondlist (int[3]). */
typedef struct { int32_t i, j, type; } bpm_bond_entry;

/* Bond coefficients of one bond type: spring k_B, multibody a_B, damping. */
typedef struct { double k, a, gamma; } bpm_bond_coeffs;

/* Pair coefficients of one type pair: k_P, contact distance d, cubic a_P, damping. */
typedef struct { double k, d, a, gamma; } bpm_pair_coeffs;

/* Energy and virial [xx, yy, zz, xy, xz, yz] of a list. */
typedef struct { double energy; double virial[6]; } bpm_tally;

/* Adds r^3 of each bond to vol and r0^3 to vol0 (vol0 may be NULL).
 * newton != 0: both atoms get the contribution (ghosts summed by the caller);
 * newton == 0: only atoms below n_owned. */
int bpm_bond_volumes(const double *x, int64_t nall, const bpm_bond_entry *bonds, int64_t nbonds,
                     const double *r0, int64_t n_owned, int32_t newton, double *vol, double *vol0);

/* Adds bond forces to f (3 nall doubles) and writes energy and virial to tally
 * (tally == NULL: not written, for steps that record nothing; with newton on
 * they are then not summed at all). Returns BPM_ERR_UNSTABLE and writes the
 * first faulty bond to fault (if not NULL) when a bond left the model's range.
 * v == NULL drops damping; vol == NULL drops the multibody term.
 * coeffs[type - 1] holds the coefficients of bond type `type`. */
int bpm_bond_forces(const double *x, const double *v, int64_t nall, const bpm_bond_entry *bonds,
                    int64_t nbonds, const double *r0, const bpm_bond_coeffs *coeffs, int64_t ncoeffs,
                    const double *vol, const double *vol0, int64_t n_owned, int32_t newton, double *f,
                    bpm_tally *tally, bpm_fault *fault);

/* Bonds that break and yield (bond styles bpm/spring/rs and
 * bpm/spring/plastic/rs; docs/model.md, "Breaking and yielding"): how the
 * bonds of one type fail. A bond breaks when |r - r0| / r0 exceeds
 * critical_strain (if breaks); smooth multiplies its force by
 * 1 - (e / critical_strain)^8; with yields, its plastic strain e_p moves so
 * that |e - e_p| <= plastic_strain; normalize puts the spring on strain. */
typedef struct {
  double critical_strain, plastic_strain;
  int32_t breaks, smooth, normalize, yields;
} bpm_bond_failure;

/* What a failing pass found: bonds broken, bonds whose e_p moved. */
typedef struct { int64_t broken, yielded; } bpm_failure_counts;

/* BPM_OK if the model can use rule; else BPM_ERR_STOPPED and why, naming
 * the value, in message (len bytes). */
int bpm_check_bond_failure(const bpm_bond_failure *rule, char *message, int64_t len);

/* As bpm_bond_volumes over the intact bonds (type > 0), with the rest
 * lengths (1 + e_p) r0 in vol0 (plastic == NULL: e_p = 0); vol0 required. */
int bpm_intact_bond_volumes(const double *x, int64_t nall, const bpm_bond_entry *bonds,
                            int64_t nbonds, const double *r0, const double *plastic,
                            int64_t n_owned, int32_t newton, double *vol, double *vol0);

/* As bpm_bond_forces for bonds that break and yield (rules[type - 1]):
 * entries of type 0 or below are skipped; a bond that breaks gets type 0 and its
 * list index goes to broken (nbonds slots); plastic (NULL when no rule
 * yields) holds each bond's e_p, updated; may_break == 0 keeps every bond
 * (a run's set-up). Counts to found (if not NULL). */
int bpm_failing_bond_forces(const double *x, const double *v, int64_t nall, bpm_bond_entry *bonds,
                            int64_t nbonds, const double *r0, double *plastic,
                            const bpm_bond_coeffs *coeffs, const bpm_bond_failure *rules,
                            int64_t ncoeffs, int32_t may_break, const double *vol,
                            const double *vol0, int64_t n_owned, int32_t newton, double *f,
                            int32_t *broken, bpm_failure_counts *found, bpm_tally *tally,
                            bpm_fault *fault);

/* A bond list's intact bonds kept as rows between steps (one bond type;
 * steps without energy or virial): create once, sync every step with the
 * list (rebuilt only when builds, edits, nbonds or nall changed; *stale = 1
 * when V0 must be summed and set), then volumes (V of atoms 0..ngather,
 * and V0 into vol0 if not NULL: with newton == 0, after breaks only, the
 * broken bonds' atoms summed anew and the others as set_reference last got
 * them), set_reference after V0 is communicated,
 * and forces (onto atoms 0..ngather; vol NULL: no multibody term). The
 * same forces, breaks and plastic strains as bpm_failing_bond_forces. */
typedef struct bpm_list_rows bpm_list_rows;
bpm_list_rows *bpm_list_rows_create(void);
void bpm_list_rows_destroy(bpm_list_rows *rows);
int bpm_list_rows_sync(bpm_list_rows *rows, int64_t builds, int64_t edits,
                       const bpm_bond_entry *bonds, int64_t nbonds, const double *r0,
                       const double *plastic, int64_t nall, int32_t *stale);
int bpm_list_rows_volumes(bpm_list_rows *rows, const double *x, int64_t nall, int64_t ngather,
                          int32_t newton, double *vol, double *vol0);
int bpm_list_rows_set_reference(bpm_list_rows *rows, const double *vol0, int64_t nall);
int bpm_list_rows_forces(bpm_list_rows *rows, const double *x, const double *v, int64_t nall,
                         const bpm_bond_coeffs *coeffs, const bpm_bond_failure *rule,
                         int32_t may_break, const double *vol, int64_t ngather, double *f,
                         bpm_bond_entry *bonds, int64_t nbonds, double *plastic, int32_t *broken,
                         bpm_failure_counts *found, bpm_fault *fault);

/* Force over distance (to fforce) and spring-proxy energy (k (r - r_eq)^2
 * / 2, over r0 with normalize) of one intact bond with plastic strain e_p,
 * without damping or multibody term; both 0 past the critical strain. */
double bpm_failing_bond_single(double r, double r0, double e_p, const bpm_bond_coeffs *coeffs,
                               const bpm_bond_failure *rule, double *fforce);

/* Zero-net-multibody variant, first pass: adds each bond's multibody force
 * and a count of 1 to sums[4 i .. 4 i + 3] = (Mx, My, Mz, N) of its atoms
 * (owned ones only with newton == 0). vol, vol0: complete volumes. */
int bpm_multibody_sums(const double *x, int64_t nall, const bpm_bond_entry *bonds, int64_t nbonds,
                       const double *r0, const bpm_bond_coeffs *coeffs, int64_t ncoeffs,
                       const double *vol, const double *vol0, int64_t n_owned, int32_t newton,
                       double *sums);

/* Zero-net-multibody variant, second pass: adds -(M_i/N_i - M_j/N_j)/2 of
 * each bond to atom i and the opposite to j, from sums complete on every
 * atom (ghosts included); its virial (no energy) to tally if not NULL. */
int bpm_balance_multibody(const double *x, int64_t nall, const bpm_bond_entry *bonds,
                          int64_t nbonds, const double *sums, int64_t n_owned, int32_t newton,
                          double *f, bpm_tally *tally);

/* Adds contact forces over a LAMMPS half neighbour list (ilist, numneigh,
 * firstneigh; special bits in the top two bits of each neighbour index).
 * types == NULL: every atom is type 1. coeffs is ntypes x ntypes, row-major,
 * 0-based ((ti-1) * ntypes + (tj-1)). special holds LAMMPS's special_lj[4].
 * damping_taper != 0: the damping fades as 1 - (r/d)^8 (upstream's
 * pair_style bpm/spring; the model's contact has no such factor).
 * Energy and virial go to tally; tally == NULL: not summed or written.
 * BPM_ERR_UNSTABLE and fault as for bpm_bond_forces (a non-finite pair force). */
int bpm_pair_forces(const double *x, const double *v, const int32_t *types, int64_t nall,
                    int64_t ntypes, const bpm_pair_coeffs *coeffs, int64_t inum, const int32_t *ilist,
                    const int32_t *numneigh, const int32_t *const *firstneigh, const double *special,
                    int32_t damping_taper, int64_t n_owned, int32_t newton, double *f,
                    bpm_tally *tally,
                    bpm_fault *fault);

/* The message for a fault (what happened at step, naming the atoms name_i and
 * name_j, and the likely cause at timestep dt for the bond's coefficients,
 * NULL for a pair, and the first atom's mass) into buf, NUL-terminated, cut
 * to len bytes. Returns the full length, or minus a BPM_ERR_* status. */
int64_t bpm_describe_fault(const bpm_fault *fault, int64_t name_i, int64_t name_j, int64_t step,
                           double dt, const bpm_bond_coeffs *bond, double mass, char *buf,
                           int64_t len);

/* Force over distance (written to fforce) and spring-proxy energy of one
 * bond without damping, for LAMMPS's Bond::single. */
double bpm_bond_single(double r, double r0, double dilation, const bpm_bond_coeffs *coeffs,
                       double *fforce);

/* pair_style bpm/granular (src/ffi/granular.rs): DEM sphere contacts with
 * the optional multi-contact closure. A handle holds the coefficients and
 * the passes' buffers. Each owned atom carries a contact-memory row of
 * 1 + 9 slots doubles ([count, (partner tag, 8 values) x slots]); every
 * atom a correction row of 1 + 2 slots ([count, (partner tag, Delta) x
 * slots]), owned rows written by the corrections pass, ghost rows copied
 * from their owners before the forces pass. Needs newton off for pairs. */
typedef struct bpm_granular bpm_granular;

/* The arrays of a pass: nall atoms (x, v, omega as 3 nall doubles; radius,
 * rmass nall; tag nall IDs), the first nlocal owned. */
typedef struct {
  const double *x, *v, *omega, *radius, *rmass;
  const int64_t *tag;
  int64_t nall, nlocal;
} bpm_granular_atoms;

/* Parses the nwords words of pair_coeff after "* *"; NULL on bad input,
 * with the reason in message (len bytes). */
bpm_granular *bpm_granular_create(int32_t nwords, const char *const *words, char *message,
                                  int64_t len);
void bpm_granular_destroy(bpm_granular *style);
/* Contacts per row. */
int64_t bpm_granular_slots(const bpm_granular *style);
/* Pair cutoff for spheres up to max_radius (the closure's reach included). */
double bpm_granular_cutoff(const bpm_granular *style, double max_radius);
/* Whether the closure is on (corrections pass and ghost copy needed). */
int32_t bpm_granular_has_closure(const bpm_granular *style);
/* What pass 1 found: the largest correction over its atom's radius, and
 * the contacts (or terms) the advanced closure switched off. */
typedef struct { double largest; int64_t switched_off; } bpm_granular_summary;

/* Pass 1: owned rows of corrections from the memory rows; summary if not NULL. */
int bpm_granular_corrections(bpm_granular *style, const bpm_granular_atoms *atoms, int64_t inum,
                             const int32_t *ilist, const int32_t *numneigh,
                             const int32_t *const *firstneigh, const double *history,
                             double *corrections, int64_t step, bpm_granular_summary *summary,
                             char *message, int64_t len);
/* Stops (BPM_ERR_STOPPED, why in message) when a pair of periodic faces
 * (h: LAMMPS's shape matrix, 6 doubles; periodic: 3 flags) is not more
 * than twice the neighbour-list range (cutoff + skin) apart. */
int bpm_granular_check_box(double range, const double *h, const int32_t *periodic, int64_t step,
                           char *message, int64_t len);
/* Pass 2: forces and torques on owned atoms, memory rows advanced when
 * update != 0 and renewed (only listed contacts kept) when renew != 0;
 * virial to tally if not NULL. */
int bpm_granular_forces(bpm_granular *style, const bpm_granular_atoms *atoms, int64_t inum,
                        const int32_t *ilist, const int32_t *numneigh,
                        const int32_t *const *firstneigh, const double *corrections,
                        double *history, double *f, double *torque, double dt, int32_t update,
                        int32_t renew, int64_t step, bpm_tally *tally, char *message, int64_t len);

/* fix bpm/granular/wall: a flat wall whose contacts the pair style computes
 * in both passes, kept in the same rows under the partner ID -number. Its
 * material is parsed from the words of pair_coeff's material (no
 * multicontact, no slots); NULL on bad input, with why in message. */
typedef struct bpm_granular_wall_material bpm_granular_wall_material;
bpm_granular_wall_material *bpm_granular_wall_material_create(int32_t nwords,
                                                              const char *const *words,
                                                              char *message, int64_t len);
void bpm_granular_wall_material_destroy(bpm_granular_wall_material *material);

/* One wall at a force evaluation: the plane x[axis] = position moving at
 * velocity, its atoms on side +1 (above) or -1 (below); fresh != 0 when it
 * was (re)defined since the last evaluation (its friction springs restart,
 * unless keep != 0 and the wall it replaces had its number, axis and side). */
typedef struct {
  int64_t number;
  int32_t axis, side;
  double position, velocity;
  int32_t fresh, keep;
  const bpm_granular_wall_material *material;
} bpm_granular_wall;

/* Sets the walls of the coming passes (before pass 1), restarting fresh
 * walls' springs in the nlocal memory rows; BPM_ERR_STOPPED with why in
 * message for bad walls. */
int bpm_granular_set_walls(bpm_granular *style, const bpm_granular_wall *walls, int64_t nwalls,
                           double *history, int64_t nlocal, char *message, int64_t len);
/* A handle made anew (a later pair_coeff) takes over the walls the old one
 * saw last, so walls defined anew keep their loads. */
int bpm_granular_inherit_walls(bpm_granular *to, const bpm_granular *from);
/* After pass 2: the normal force on each of the nwalls walls from this
 * rank's atoms (positive when pushed). */
int bpm_granular_wall_forces(const bpm_granular *style, double *out, int64_t nwalls);

#ifdef __cplusplus
}
#endif

#endif
