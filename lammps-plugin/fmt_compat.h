/* Debian's liblammps-dev (20220106) headers include "fmt/format.h" but do
 * not ship it, and call fmt::make_args_checked, which fmt 9 removed.
 * Debian's libfmt-dev (9.x) provides the header; this restores the one
 * missing name. Include it before any LAMMPS header. Modern LAMMPS ships
 * its own fmt, and then this header does nothing. */
#ifndef BPM_FMT_COMPAT_H
#define BPM_FMT_COMPAT_H

#if !defined(BPM_MODERN_LAMMPS)
#include <fmt/format.h>
#include <type_traits>

#if FMT_VERSION >= 90000
namespace fmt {
template <typename... Args, typename S>
inline auto make_args_checked(const S &, const std::remove_reference_t<Args> &...args)
{
  return fmt::make_format_args(args...);
}
}    // namespace fmt
#endif
#endif

#endif
