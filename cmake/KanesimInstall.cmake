# `cmake --install build --prefix PREFIX`: the kanesim command, its documentation and the
# examples, in the GNU layout:
#   PREFIX/bin/kanesim                       (the standard library is embedded)
#   PREFIX/share/doc/kanesim/README.md, *.md, images/, benchmarks/, constraints/
#   PREFIX/share/doc/kanesim/examples/*.mech
# The Python module is not part of it (component `python`, installed by pip).
include(GNUInstallDirs)
# The binary keeps the run path of the libraries it was linked with outside the build tree
# (OpenMPI's libmpi lives in a directory of its own) and is installed as built: no run path
# to rewrite (CMake's rewrite fails on the build's "dir:" form of it).
set_target_properties(kanesim PROPERTIES BUILD_WITH_INSTALL_RPATH ON INSTALL_RPATH_USE_LINK_PATH ON)
install(TARGETS kanesim RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT cli)
# The modules kanesim opens with dlopen when a command needs them (util/dynamic_module.h):
# mesh import and glTF export (assimp), the viewer's HTTP server, MPI sweeps. The installed
# binary looks for them in PREFIX/<libdir>/kanesim, before the build tree's copies.
foreach(module kanesim_geometry_assimp kanesim_viz_http kanesim_batch_mpi)
  if(TARGET ${module})
    install(TARGETS ${module} LIBRARY DESTINATION ${KANESIM_MODULE_INSTALL_DIR} COMPONENT cli)
  endif()
endforeach()
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT docs)
file(GLOB KANESIM_DOC_PAGES ${PROJECT_SOURCE_DIR}/docs/*.md)
install(FILES ${KANESIM_DOC_PAGES} DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT docs)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/images DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT docs)
# The dated history pages the current ones link to (docs/benchmarks/*.md with their plots,
# docs/constraints/*.md), so that the links of an installed page resolve as in the repository.
foreach(history benchmarks constraints)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/${history} DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT docs
          FILES_MATCHING PATTERN "*.md" PATTERN "*.png")
endforeach()
file(GLOB KANESIM_EXAMPLE_FILES ${PROJECT_SOURCE_DIR}/examples/*.mech)
install(FILES ${KANESIM_EXAMPLE_FILES} DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples COMPONENT examples)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/meshes DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples COMPONENT examples)

if(KANESIM_BUILD_TESTS)
  # Installs this build into a fresh temporary prefix and runs an example from there.
  add_test(NAME install.prefix
           COMMAND ${CMAKE_COMMAND} -DBUILD=${CMAKE_BINARY_DIR} -DPREFIX=${CMAKE_BINARY_DIR}/install-test
                   -DDOCDIR=${CMAKE_INSTALL_DOCDIR} -DBINDIR=${CMAKE_INSTALL_BINDIR}
                   -DMODULEDIR=${KANESIM_MODULE_INSTALL_DIR}
                   -P ${PROJECT_SOURCE_DIR}/cmake/install_test.cmake)
endif()
