# METIS (Debian's libmetis-dev): the MPI mesh example, tests and benchmark
# partition with it; dpsm itself does not need it. Defines the imported
# target dpsm_metis when it is found.
find_path(DPSM_METIS_INCLUDE_DIR metis.h)
find_library(DPSM_METIS_LIBRARY metis)
if(DPSM_METIS_INCLUDE_DIR AND DPSM_METIS_LIBRARY AND NOT TARGET dpsm_metis)
  add_library(dpsm_metis UNKNOWN IMPORTED GLOBAL)
  set_target_properties(dpsm_metis PROPERTIES IMPORTED_LOCATION "${DPSM_METIS_LIBRARY}"
                                              INTERFACE_INCLUDE_DIRECTORIES "${DPSM_METIS_INCLUDE_DIR}")
endif()
