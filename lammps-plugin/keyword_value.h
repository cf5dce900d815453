/* A yes/no keyword value as LAMMPS reads it (utils::logical, which older
 * LAMMPS versions lack): yes, no, on, off, true, false, 1, 0. */
#ifndef BPM_KEYWORD_VALUE_H
#define BPM_KEYWORD_VALUE_H

#include "error.h"
#include "lammps.h"

#include <string>

inline bool bpm_yes_no(LAMMPS_NS::LAMMPS *lmp, const std::string &style, const std::string &keyword,
                       const std::string &value)
{
  if (value == "yes" || value == "on" || value == "true" || value == "1") return true;
  if (value == "no" || value == "off" || value == "false" || value == "0") return false;
  lmp->error->all(FLERR, style + ": " + keyword + " takes yes or no, got '" + value + "'");
  return false;
}

#endif
