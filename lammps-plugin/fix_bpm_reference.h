/* Internal fix of our bond styles: per-bond reference lengths r0 (and,
 * created with the word "plastic", plastic strains e_p), stored per atom
 * beside atom->bond_atom so they move with atoms between ranks and go into
 * restart files, and the volume proxies V, V0 with their ghost
 * communication, and the multibody sums of the zero-net variant. Created
 * by the bond style with ID BPM_REFERENCE. */
#ifndef LMP_FIX_BPM_REFERENCE_H
#define LMP_FIX_BPM_REFERENCE_H

#include "fix.h"
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace LAMMPS_NS {

class FixBPMReference : public Fix {
 public:
  FixBPMReference(class LAMMPS *, int, char **);
  ~FixBPMReference() override;
  int setmask() override;
  void setup_pre_force(int) override;
  int modify_param(int, char **) override;

  void grow_arrays(int) override;
  void copy_arrays(int, int, int) override;
  int pack_exchange(int, double *) override;
  int unpack_exchange(int, double *) override;
  int pack_restart(int, double *) override;
  void unpack_restart(int, int) override;
  int size_restart(int) override;
  int maxsize_restart() override;
  void write_restart(FILE *) override;
  void restart(char *) override;

  int pack_forward_comm(int, int *, double *, int, int *) override;
  void unpack_forward_comm(int, int, double *) override;
  int pack_reverse_comm(int, int, double *) override;
  void unpack_reverse_comm(int, int *, double *) override;
  double memory_usage() override;

  // r0 of each entry of neighbor->bondlist, rebuilt when the list changes
  // (0 for entries of broken bonds, type 0).
  const double *bondlist_r0();
  // e_p of each entry of neighbor->bondlist, for the kernels to update
  // (fixes created with "plastic"); call bondlist_r0 first.
  double *bondlist_plastic() { return list_ep.data(); }
  // Writes the list's e_p back to the slots of the bonds' owned atoms.
  void store_plastic();
  // Forgets slot m of owned atom i: the last slot moves into it, as the
  // bond style moves the atom's last bond into a broken bond's place.
  void remove_slot(int i, int m);
  bool plastic() const { return with_plastic; }
  // Read from a restart file written by a style whose bonds never break.
  bool restored_unbreakable() const { return restored && captured && !restored_breaking; }
  // Recorded in restart files: whether the owning style breaks bonds.
  void set_breaking(bool on) { breaking = on; }
  // The owning style in messages, e.g. "bond_style bpm/multibody".
  std::string owner;
  // Zeroed V and V0 arrays for nall atoms.
  void clear_volumes(int nall);
  // V and V0 arrays for nall atoms, as they are (grown if needed: then unset).
  void ensure_volumes(int nall);
  // Sums ghost parts into owners (newton_bond on), then copies owners to
  // ghosts: V, and V0 too unless with_reference is false.
  void communicate_volumes(int newton_bond, bool with_reference = true);
  // Zeroed multibody sums (Mx, My, Mz, N per atom) of the zero-net variant.
  void clear_multibody_sums(int nall);
  // As communicate_volumes, for the multibody sums.
  void communicate_multibody_sums(int newton_bond);
  // r0 of the bond between local atoms i and j (-1 if none).
  double r0_between(int i, int j);
  // r0 and e_p (0 without plastic strains) of that bond; false if none.
  bool bond_values(int i, int j, double &r0_value, double &ep_value);
  double max_r0() const { return max_r0_all; }
  // How many times the list-aligned r0 and e_p were built (each neighbour
  // build, each run's set-up): what a copy of them must follow.
  bigint list_builds() const { return list_rebuilds; }

  double *vol, *vol0;
  double *multibody_sums;    // [4 nall]: the zero-net variant's multibody sums

 private:
  double **r0;    // [nmax][bond_per_atom], aligned with atom->bond_atom
  double **ep;    // likewise, e_p (with_plastic only)
  bool with_plastic;
  bool breaking, restored, restored_breaking;
  int captured;
  int nmax_vol;
  bool comm_reference;    // V0 travels with V
  int nmax_sums;
  int nmax_r0;
  int stride;
  std::vector<double> list_r0, list_ep;
  std::vector<long> list_slot_i, list_slot_j;    // i * stride + m of the owned atoms' slots, or -1
  std::vector<long> slot_entry;    // per slot: 2 k + side of the list entry that uses it, or -1
  bool slots_stale;
  bigint list_built_at;
  bigint list_rebuilds;
  int list_size;
  double max_r0_all;
  bool comm_sums;    // which arrays the comm calls carry: the multibody sums, or V and V0
  void communicate(int newton_bond);
  std::map<std::pair<tagint, tagint>, double> given;    // from "lengths FILE"
  void capture();
  void find_slots();
  long slot_of(int a, int b) const;
  void read_lengths(const char *path);
};

}    // namespace LAMMPS_NS

#endif
