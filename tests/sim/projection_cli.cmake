# `kanesim run --projection step` and the default (`eval`) on the four-bar at rtol 1e-10
# over 2 s: the crank angle at 2 s matches the mpmath reference (bench/data/fourbar_ref.csv,
# -3.092144849314689) to 8 decimals (measured 4.6e-10 and 5.3e-10 off); and an unknown
# value is a usage error (exit code 1, the accepted values named).
# Usage: cmake -DKANESIM=... -DMECH=... -DOUT=<prefix> -P projection_cli.cmake
foreach(mode eval step)
  execute_process(COMMAND ${KANESIM} run ${MECH} --integrator dop853 --projection ${mode} --rtol 1e-10
                          --stop-time 2 --interval 1 --output crank_pivot.q -o ${OUT}_${mode}.csv
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "--projection ${mode} exited with ${rc}:\n${err}")
  endif()
  file(STRINGS ${OUT}_${mode}.csv lines)
  list(GET lines -1 last)
  string(REGEX REPLACE "^[^,]*,([^,]*).*$" "\\1" q_${mode} "${last}")
endforeach()
# CMake has no floating-point arithmetic: the printed numbers' first 11 characters.
foreach(mode eval step)
  string(SUBSTRING "${q_${mode}}" 0 11 head)
  if(NOT head STREQUAL "-3.09214484")
    message(FATAL_ERROR "--projection ${mode}: crank angle at 2 s ${q_${mode}}, reference -3.092144849314689")
  endif()
endforeach()
execute_process(COMMAND ${KANESIM} run ${MECH} --projection sometimes --stop-time 1 -o ${OUT}_bad.csv
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "eval" OR NOT err MATCHES "step")
  message(FATAL_ERROR "--projection sometimes: exit ${rc}, expected 1 and the accepted values:\n${err}")
endif()
