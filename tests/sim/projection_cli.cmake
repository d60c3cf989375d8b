# `kanesim run --projection step` against the default (`eval`) on the four-bar: both at
# rtol 1e-10 over 2 s, the crank angle at 2 s (-3.0921448...) agrees to the 8 decimals
# (measured 6.5e-11 apart); and an unknown value is a usage error (exit code 1, the
# accepted values named).
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
# CMake has no floating-point arithmetic: the printed numbers' first 11 characters
# ("-3.09214484"), a difference below 1e-8.
string(SUBSTRING "${q_eval}" 0 11 a)
string(SUBSTRING "${q_step}" 0 11 b)
if(NOT a STREQUAL b)
  message(FATAL_ERROR "crank angle at 2 s: ${q_eval} (eval) vs ${q_step} (step)")
endif()
execute_process(COMMAND ${KANESIM} run ${MECH} --projection sometimes --stop-time 1 -o ${OUT}_bad.csv
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "eval" OR NOT err MATCHES "step")
  message(FATAL_ERROR "--projection sometimes: exit ${rc}, expected 1 and the accepted values:\n${err}")
endif()
