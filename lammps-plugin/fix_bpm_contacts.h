/* Internal fix of pair_style bpm/granular: the per-atom rows of the contact
 * memory (moved with atoms between ranks, written to restart files) and the
 * rows of multi-contact corrections (copied from owners to ghosts). The
 * rows' layout and meaning belong to the kernels (bpm_kernels.h); this fix
 * only stores and moves them. Created by the pair style with ID
 * BPM_CONTACTS. */
#ifndef LMP_FIX_BPM_CONTACTS_H
#define LMP_FIX_BPM_CONTACTS_H

#include "fix.h"

namespace LAMMPS_NS {

class FixBPMContacts : public Fix {
 public:
  FixBPMContacts(class LAMMPS *, int, char **);
  ~FixBPMContacts() override;
  int setmask() override;

  void grow_arrays(int) override;
  void copy_arrays(int, int, int) override;
  void set_arrays(int) override;
  int pack_exchange(int, double *) override;
  int unpack_exchange(int, double *) override;
  int pack_restart(int, double *) override;
  void unpack_restart(int, int) override;
  int size_restart(int) override;
  int maxsize_restart() override;

  int pack_forward_comm(int, int *, double *, int, int *) override;
  void unpack_forward_comm(int, int, double *) override;
  double memory_usage() override;

  int slots() const { return nslots; }
  // The memory rows of owned atoms, contiguous.
  double *memory_rows() { return rows ? rows[0] : nullptr; }
  // Correction rows for nall atoms, contiguous (owned rows are the kernels' to write).
  double *correction_rows(int nall);
  // Copies owned atoms' correction rows to their ghosts.
  void forward_corrections();

 private:
  int nslots, memory_stride, correction_stride;
  double **rows;    // [nmax][memory_stride]
  int nmax_rows;
  double *corrections;   // [ncorrections * correction_stride]
  int ncorrections;
  int used(const double *row) const { return 1 + static_cast<int>(row[0]) * 9; }
};

}    // namespace LAMMPS_NS

#endif
