# An imported robot's animation (its <visual> boxes, cylinders and spheres; Panda's DAE meshes
# when example-robot-data is in bench/.venv) is valid glTF 2.0 for the Khronos validator. If
# this fails, a visual the importer wrote is drawn into a file other viewers refuse.
# Skipped without the validator (scripts/setup.sh: npm ci in tests/tools).
if(NOT EXISTS ${SRC}/tests/tools/node_modules/gltf-validator)
  message(STATUS "gltf-validator not installed: skipped")
  return()
endif()
file(MAKE_DIRECTORY ${WORK})
set(files ${WORK}/every_joint.glb)
execute_process(COMMAND ${KANESIM} run ${SRC}/tests/import/data/every_joint.urdf --stop-time 0.2 -o ${WORK}/ej.csv
                        --animation ${WORK}/every_joint.glb RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "run every_joint.urdf: exit ${rc}\n${err}")
endif()
file(GLOB share ${SRC}/bench/.venv/lib/python3*/site-packages/cmeel.prefix/share)
if(share)
  execute_process(COMMAND ${KANESIM} run ${SRC}/tests/import/data/panda.urdf --package-path ${share} --stop-time 0.1
                          -o ${WORK}/panda.csv --animation ${WORK}/panda.glb RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "run panda.urdf: exit ${rc}\n${err}")
  endif()
  list(APPEND files ${WORK}/panda.glb)
endif()
execute_process(COMMAND node ${SRC}/tests/tools/validate_gltf.js ${files} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
message(STATUS "${out}")
if(NOT rc EQUAL 0 OR out MATCHES "[1-9][0-9]* errors")
  message(FATAL_ERROR "the validator found errors")
endif()
