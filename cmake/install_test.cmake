# ctest install.prefix: `cmake --install BUILD --prefix PREFIX` into an empty PREFIX, then
# the installed kanesim runs an installed example from a directory outside the source and
# build trees, and its first row is the example's initial state.
file(REMOVE_RECURSE ${PREFIX})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${PREFIX} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${rc}):\n${out}\n${err}")
endif()
# The history pages benchmarks.md and constraints.md link to come along.
foreach(f ${BINDIR}/kanesim ${DOCDIR}/README.md ${DOCDIR}/language.md ${DOCDIR}/python.md
          ${DOCDIR}/examples/double_pendulum.mech ${DOCDIR}/benchmarks/2026-11-28_change_points_history.md
          ${DOCDIR}/constraints/singular_configurations.md)
  if(NOT EXISTS ${PREFIX}/${f})
    message(FATAL_ERROR "not installed: ${PREFIX}/${f}")
  endif()
endforeach()
if(EXISTS ${PREFIX}/kanesim/__init__.py OR EXISTS ${PREFIX}/lib/kanesim/__init__.py)
  message(FATAL_ERROR "the Python module was installed by cmake --install (it is pip's)")
endif()
set(work ${PREFIX}/work)
file(MAKE_DIRECTORY ${work})
execute_process(COMMAND ${PREFIX}/${BINDIR}/kanesim run ${PREFIX}/${DOCDIR}/examples/double_pendulum.mech
                        --stop-time 0.1 -o out.csv
                WORKING_DIRECTORY ${work} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the installed kanesim failed (${rc}):\n${err}")
endif()
file(STRINGS ${work}/out.csv lines)
list(LENGTH lines n)
list(GET lines 0 header)
list(GET lines 1 first)
if(NOT n EQUAL 12 OR NOT header STREQUAL "time,shoulder.q,shoulder.u,elbow.q,elbow.u"
   OR NOT first STREQUAL "0,1.5707963267948966,0,1.5707963267948966,0")
  message(FATAL_ERROR "unexpected output of the installed kanesim (${n} lines):\n${header}\n${first}")
endif()

# The mesh example from the prefix, with its animation: the installed mesh module
# (PREFIX/MODULEDIR/libkanesim_geometry_assimp.so) reads the STL parts and writes the glTF.
set(assimp_module ${PREFIX}/${MODULEDIR}/libkanesim_geometry_assimp.so)
if(NOT EXISTS ${assimp_module} OR NOT EXISTS ${PREFIX}/${MODULEDIR}/libkanesim_viz_http.so)
  message(FATAL_ERROR "the dlopen modules were not installed in ${PREFIX}/${MODULEDIR}")
endif()
set(ENV{KANESIM_GEOMETRY_MODULE} ${assimp_module})
execute_process(COMMAND ${PREFIX}/${BINDIR}/kanesim run ${PREFIX}/${DOCDIR}/examples/slider_crank_meshes.mech
                        --stop-time 0.1 -o meshes.csv --animation meshes.glb
                WORKING_DIRECTORY ${work} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS ${work}/meshes.glb)
  message(FATAL_ERROR "the installed kanesim failed on the mesh example (${rc}):\n${err}")
endif()
# The FMU's library beside the modules: the installed kanesim exports an FMU that carries it.
if(NOT EXISTS ${PREFIX}/${MODULEDIR}/fmu/kanesim_fmu.so)
  message(FATAL_ERROR "the FMU library was not installed in ${PREFIX}/${MODULEDIR}/fmu")
endif()
execute_process(COMMAND ${PREFIX}/${BINDIR}/kanesim export ${PREFIX}/${DOCDIR}/examples/double_pendulum.mech
                        --fmi 2 -o dp.fmu
                WORKING_DIRECTORY ${work} RESULT_VARIABLE rc ERROR_VARIABLE err)
file(SIZE ${work}/dp.fmu fmu_size)
if(NOT rc EQUAL 0 OR fmu_size LESS 100000)
  message(FATAL_ERROR "the installed kanesim did not export an FMU with its library (${rc}):\n${err}")
endif()
message(STATUS "installed into ${PREFIX}; the installed kanesim ran examples/double_pendulum.mech and "
               "examples/slider_crank_meshes.mech (--animation) with the installed mesh module")
