# Finds SuiteSparse KLU (Debian 12's SuiteSparse 5 ships no CMake config for it).
# Defines the imported target KLU::KLU: the shared libraries, or, for a program whose property
# KANESIM_STATIC_RUNTIME is ON (the kanesim command, cli/CMakeLists.txt), the static archives
# when the package has all of them (five shared libraries fewer to map at every start).
find_path(KLU_INCLUDE_DIR klu.h PATH_SUFFIXES suitesparse)
find_library(KLU_LIBRARY klu)
find_library(KLU_AMD_LIBRARY amd)
find_library(KLU_COLAMD_LIBRARY colamd)
find_library(KLU_BTF_LIBRARY btf)
find_library(KLU_SSCONFIG_LIBRARY suitesparseconfig)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(KLU REQUIRED_VARS KLU_LIBRARY KLU_INCLUDE_DIR KLU_AMD_LIBRARY
                                  KLU_COLAMD_LIBRARY KLU_BTF_LIBRARY KLU_SSCONFIG_LIBRARY)
if(KLU_FOUND AND NOT TARGET KLU::KLU)
  set(KLU_SHARED_LIBRARIES ${KLU_LIBRARY} ${KLU_AMD_LIBRARY} ${KLU_COLAMD_LIBRARY} ${KLU_BTF_LIBRARY}
                           ${KLU_SSCONFIG_LIBRARY})
  set(KLU_ARCHIVES)
  foreach(part klu amd colamd btf suitesparseconfig)  # dependents first (ld reads archives left to right)
    find_library(KLU_${part}_ARCHIVE lib${part}.a)
    mark_as_advanced(KLU_${part}_ARCHIVE)
    if(KLU_${part}_ARCHIVE)
      list(APPEND KLU_ARCHIVES ${KLU_${part}_ARCHIVE})
    endif()
  endforeach()
  list(LENGTH KLU_ARCHIVES n)
  if(NOT n EQUAL 5)
    set(KLU_ARCHIVES ${KLU_SHARED_LIBRARIES})
  endif()
  add_library(KLU::KLU INTERFACE IMPORTED)
  set_target_properties(KLU::KLU PROPERTIES INTERFACE_INCLUDE_DIRECTORIES ${KLU_INCLUDE_DIR})
  set(static_head "$<BOOL:$<TARGET_PROPERTY:KANESIM_STATIC_RUNTIME>>")
  target_link_libraries(KLU::KLU INTERFACE "$<${static_head}:${KLU_ARCHIVES}>"
                        "$<$<NOT:${static_head}>:${KLU_SHARED_LIBRARIES}>" m)
endif()
mark_as_advanced(KLU_INCLUDE_DIR KLU_LIBRARY KLU_AMD_LIBRARY KLU_COLAMD_LIBRARY KLU_BTF_LIBRARY
                 KLU_SSCONFIG_LIBRARY)
