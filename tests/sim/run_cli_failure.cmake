# Runs `kanesim run MECH -o OUT` on a model that fails numerically and checks: exit code
# 2, the message `kanesim: numerical failure at t = <time>: <cause>` with the time near
# FAIL_NEAR, and the rows before the failure kept in OUT (header + at least MIN_ROWS).
# Usage: cmake -DKANESIM=... -DMECH=... -DOUT=... -DMIN_ROWS=5 -DFAIL_PREFIX=0.5 -P ...
execute_process(COMMAND ${KANESIM} run ${MECH} -o ${OUT} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 2)
  message(FATAL_ERROR "expected exit code 2, got ${rc}:\n${err}")
endif()
if(NOT err MATCHES "kanesim: numerical failure at t = ${FAIL_PREFIX}[0-9]*: NaN")
  message(FATAL_ERROR "unexpected message:\n${err}")
endif()
file(STRINGS ${OUT} lines)
list(LENGTH lines n)
math(EXPR rows "${n} - 1")
if(rows LESS MIN_ROWS)
  message(FATAL_ERROR "expected at least ${MIN_ROWS} rows kept, got ${rows}")
endif()
