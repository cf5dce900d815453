/* Registration of the styles: with Debian's LAMMPS (no PLUGIN package) by
 * inserting creators into the style maps through the library handle, and,
 * built with -DBPM_MODERN_LAMMPS against a LAMMPS with the PLUGIN package,
 * through the standard entry point for `plugin load`. */
#include "fmt_compat.h"

#include "bond_bpm_multibody.h"
#include "bond_bpm_spring_rs.h"
#include "fix_bpm_broken_pairs.h"
#include "fix_bpm_contacts.h"
#include "fix_bpm_granular_wall.h"
#include "fix_bpm_reference.h"
#include "fix_bpm_store_local.h"
#include "pair_bpm_contact.h"
#include "pair_bpm_granular.h"
#include "pair_bpm_spring_rs.h"

#include "force.h"
#include "input.h"
#include "lammps.h"
#include "modify.h"

#include <mpi.h>

using namespace LAMMPS_NS;

static Bond *bond_creator(LAMMPS *lmp)
{
  return new BondBPMMultibody(lmp);
}

static Bond *spring_rs_creator(LAMMPS *lmp)
{
  return new BondBPMSpringRS(lmp, false);
}

static Bond *spring_plastic_rs_creator(LAMMPS *lmp)
{
  return new BondBPMSpringRS(lmp, true);
}

static Pair *pair_spring_rs_creator(LAMMPS *lmp)
{
  return new PairBPMSpringRS(lmp);
}

static Fix *broken_pairs_creator(LAMMPS *lmp, int narg, char **arg)
{
  return new FixBPMBrokenPairs(lmp, narg, arg);
}

static Fix *store_local_creator(LAMMPS *lmp, int narg, char **arg)
{
  return new FixBPMStoreLocal(lmp, narg, arg);
}

static Pair *pair_creator(LAMMPS *lmp)
{
  return new PairBPMContact(lmp);
}

static Pair *granular_creator(LAMMPS *lmp)
{
  return new PairBPMGranular(lmp);
}

static Fix *fix_creator(LAMMPS *lmp, int narg, char **arg)
{
  return new FixBPMReference(lmp, narg, arg);
}

static Fix *contacts_creator(LAMMPS *lmp, int narg, char **arg)
{
  return new FixBPMContacts(lmp, narg, arg);
}

static Fix *wall_creator(LAMMPS *lmp, int narg, char **arg)
{
  return new FixBPMGranularWall(lmp, narg, arg);
}

extern "C" void bpm_register_styles(void *handle)
{
  auto lmp = static_cast<LAMMPS *>(handle);
  (*lmp->force->bond_map)["bpm/multibody"] = &bond_creator;
  (*lmp->force->bond_map)["bpm/spring/rs"] = &spring_rs_creator;
  (*lmp->force->bond_map)["bpm/spring/plastic/rs"] = &spring_plastic_rs_creator;
  (*lmp->force->pair_map)["bpm/spring/rs"] = &pair_spring_rs_creator;
  (*lmp->modify->fix_map)["BPM/BROKEN/PAIRS"] = &broken_pairs_creator;
  (*lmp->modify->fix_map)["BPM/STORE/LOCAL"] = &store_local_creator;
  (*lmp->force->pair_map)["bpm/contact"] = &pair_creator;
  (*lmp->force->pair_map)["bpm/granular"] = &granular_creator;
  (*lmp->modify->fix_map)["BPM/REFERENCE"] = &fix_creator;
  (*lmp->modify->fix_map)["BPM/CONTACTS"] = &contacts_creator;
  (*lmp->modify->fix_map)["bpm/granular/wall"] = &wall_creator;
}

/* lmp-bpm: LAMMPS's own main with our styles registered. */
extern "C" int bpm_lmp_main(int argc, char **argv)
{
  MPI_Init(&argc, &argv);
  int status = 0;
  try {
    auto lmp = new LAMMPS(argc, argv, MPI_COMM_WORLD);
    bpm_register_styles(lmp);
    lmp->input->file();
    delete lmp;
  } catch (std::exception &e) {
    fprintf(stderr, "ERROR: %s\n", e.what());
    status = 1;
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  MPI_Finalize();
  return status;
}

#if defined(BPM_MODERN_LAMMPS)
#include "lammpsplugin_compat.h"

extern "C" void lammpsplugin_init(void *lmp, void *handle, void *regfunc)
{
  lammpsplugin_t plugin;
  auto register_plugin = (lammpsplugin_regfunc) regfunc;
  plugin.version = static_cast<LAMMPS *>(lmp)->version;    // the host's, so no version warning
  plugin.author = "bpm project";
  plugin.handle = handle;
  plugin.style = "bond";
  plugin.name = "bpm/multibody";
  plugin.info = "bonded particle model bond with multibody volume term";
  plugin.creator.v1 = (lammpsplugin_factory1 *) &bond_creator;
  register_plugin(&plugin, lmp);
  plugin.name = "bpm/spring/rs";
  plugin.info = "upstream's bpm/spring bond (break, smooth, volume/factor) on our kernels";
  plugin.creator.v1 = (lammpsplugin_factory1 *) &spring_rs_creator;
  register_plugin(&plugin, lmp);
  plugin.name = "bpm/spring/plastic/rs";
  plugin.info = "upstream's bpm/spring/plastic bond, with volume/factor, on our kernels";
  plugin.creator.v1 = (lammpsplugin_factory1 *) &spring_plastic_rs_creator;
  register_plugin(&plugin, lmp);
  plugin.style = "pair";
  plugin.name = "bpm/spring/rs";
  plugin.info = "upstream's bpm/spring pair style on our kernels";
  plugin.creator.v1 = (lammpsplugin_factory1 *) &pair_spring_rs_creator;
  register_plugin(&plugin, lmp);
  plugin.name = "bpm/contact";
  plugin.info = "bonded particle model contact pair style";
  plugin.creator.v1 = (lammpsplugin_factory1 *) &pair_creator;
  register_plugin(&plugin, lmp);
  plugin.name = "bpm/granular";
  plugin.info = "DEM sphere contacts with the multi-contact closure";
  plugin.creator.v1 = (lammpsplugin_factory1 *) &granular_creator;
  register_plugin(&plugin, lmp);
  plugin.style = "fix";
  plugin.name = "BPM/REFERENCE";
  plugin.info = "reference lengths of bond_style bpm/multibody (internal)";
  plugin.creator.v2 = (lammpsplugin_factory2 *) &fix_creator;
  register_plugin(&plugin, lmp);
  plugin.name = "BPM/CONTACTS";
  plugin.info = "contact rows of pair_style bpm/granular (internal)";
  plugin.creator.v2 = (lammpsplugin_factory2 *) &contacts_creator;
  register_plugin(&plugin, lmp);
  plugin.name = "BPM/BROKEN/PAIRS";
  plugin.info = "broken bonds' pairs become contacts (internal)";
  plugin.creator.v2 = (lammpsplugin_factory2 *) &broken_pairs_creator;
  register_plugin(&plugin, lmp);
  plugin.name = "BPM/STORE/LOCAL";
  plugin.info = "rows of broken bonds for store/local (internal)";
  plugin.creator.v2 = (lammpsplugin_factory2 *) &store_local_creator;
  register_plugin(&plugin, lmp);
  plugin.name = "bpm/granular/wall";
  plugin.info = "flat wall of pair_style bpm/granular (a contact of the closure)";
  plugin.creator.v2 = (lammpsplugin_factory2 *) &wall_creator;
  register_plugin(&plugin, lmp);
}
#endif
