# A URDF over 64 MiB is refused by its size, before it is read (U409, exit 1), by `import` and
# by a command given it. If this fails, a huge or endless file is read into memory first.
file(MAKE_DIRECTORY ${WORK})
set(big ${WORK}/big.urdf)
file(REMOVE ${big})
execute_process(COMMAND truncate -s 80M ${big} RESULT_VARIABLE rc)  # sparse: no disk used
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "truncate failed")
endif()
foreach(cmd import check)
  execute_process(COMMAND ${KANESIM} ${cmd} ${big} RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
  if(NOT rc EQUAL 1 OR NOT err MATCHES "big.urdf: error\\[U409\\]: the file is 83886080 bytes")
    message(FATAL_ERROR "${cmd}: exit ${rc}\n${err}")
  endif()
endforeach()
file(REMOVE ${big})
