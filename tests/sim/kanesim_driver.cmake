# bench/kanesim_driver (the work-precision benchmark's in-process runner) reports the state
# it integrated: on the four-bar at rtol 1e-10 over 2 s, with both projections and 3
# repetitions, the crank angle of its last row matches the mpmath reference
# (bench/data/fourbar_ref.csv, -3.092144849314689) to 8 decimals, as `kanesim run` does
# (projection_cli.cmake); a wrong argument is a usage error (exit code 1).
# Usage: cmake -DDRIVER=... -DMECH=... -P kanesim_driver.cmake
foreach(mode eval step)
  execute_process(COMMAND ${DRIVER} ${MECH} 2 1e-10 dop853 dense ${mode} 3
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "kanesim_driver (${mode}) exited with ${rc}:\n${err}")
  endif()
  # "wall=.. rhs=.. steps=.. names=crank_pivot.q,... last=<crank angle>,..." (no time column)
  if(NOT out MATCHES "names=crank_pivot\\.q," OR NOT out MATCHES "last=(-?[0-9.e+-]+),")
    message(FATAL_ERROR "kanesim_driver (${mode}): unexpected output\n${out}")
  endif()
  string(SUBSTRING "${CMAKE_MATCH_1}" 0 11 head)
  if(NOT head STREQUAL "-3.09214484")
    message(FATAL_ERROR "kanesim_driver (${mode}): crank angle at 2 s ${CMAKE_MATCH_1}, reference -3.092144849314689")
  endif()
endforeach()
execute_process(COMMAND ${DRIVER} ${MECH} 2 1e-6 rk45 dense eval 1 RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "usage")
  message(FATAL_ERROR "kanesim_driver with integrator rk45: exit ${rc}, expected 1 and the usage:\n${err}")
endif()
