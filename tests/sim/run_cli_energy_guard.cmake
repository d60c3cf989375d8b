# `kanesim run` with the energy guard (docs/integrators.md "The energy guard") on issue 20's
# silent wrong answer: the equal-link parallelogram (a = 0.6) on the multiplier form with
# CVODE-BDF at rtol 1e-6 leaves its branch after t = 9.73 and its energy grows from 32.5 J
# to 1424 J; at b3f6679 that run exits 0. Checks, against the same run with
# `--energy-check off`: exit code 2 with the time (before 10) and the cause, and the rows
# before the stop on disk, each one byte-identical to the unguarded run's row (the guard
# adds a stop, never changes a row). Should a fix of the cause keep the run on its branch
# (the unguarded energy then stays put), the guarded run must end with exit 0 and the
# same file: the guard must never stop a correct run.
# Usage: cmake -DKANESIM=... -DMECH=.../parallelogram.mech -DOUT=prefix -P ...
set(args run ${MECH} --set a=0.6 --solver sparse --integrator cvode-bdf --rtol 1e-6 --stop-time 20)
execute_process(COMMAND ${KANESIM} ${args} --energy-check off --output kinetic_energy --output potential_energy
                -o ${OUT}_off.csv RESULT_VARIABLE rc_off ERROR_VARIABLE err_off)
execute_process(COMMAND ${KANESIM} ${args} --output kinetic_energy --output potential_energy
                -o ${OUT}_on.csv RESULT_VARIABLE rc_on ERROR_VARIABLE err_on)
if(NOT rc_off EQUAL 0)
  message(FATAL_ERROR "the unguarded run: expected exit 0, got ${rc_off}:\n${err_off}")
endif()
file(STRINGS ${OUT}_off.csv off_lines)
file(STRINGS ${OUT}_on.csv on_lines)
list(LENGTH off_lines n_off)
list(LENGTH on_lines n_on)
# The unguarded energy at the end (row: t, T, V).
list(GET off_lines -1 last)
string(REPLACE "," ";" last "${last}")
list(GET last 1 T_end)
list(GET last 2 V_end)
math(EXPR n_on_rows "${n_on} - 1")
if(rc_on EQUAL 2)
  if(NOT err_on MATCHES "kanesim: numerical failure at t = 9[.][0-9]*: the total energy of a conservative model changed by [^\n]*the solution cannot be trusted")
    message(FATAL_ERROR "unexpected message:\n${err_on}")
  endif()
  if(n_on_rows LESS 900)
    message(FATAL_ERROR "expected the rows up to t = 9 and more on disk, got ${n_on_rows}")
  endif()
else()
  if(NOT rc_on EQUAL 0)
    message(FATAL_ERROR "expected exit 2 (or 0 if the run is now correct), got ${rc_on}:\n${err_on}")
  endif()
  # Exit 0 is right only if the run is now correct: its energy kept near 32.5 J.
  if(T_end GREATER 100)
    message(FATAL_ERROR "exit 0 with the kinetic energy at ${T_end} J at the end (32.5 J in all at the start):\n${err_on}")
  endif()
  if(NOT n_on EQUAL n_off)
    message(FATAL_ERROR "guarded ${n_on} lines, unguarded ${n_off}")
  endif()
endif()
math(EXPR last_index "${n_on} - 1")
foreach(i RANGE 0 ${last_index})
  list(GET on_lines ${i} a)
  list(GET off_lines ${i} b)
  if(NOT a STREQUAL b)
    message(FATAL_ERROR "line ${i} differs:\n  guarded   ${a}\n  unguarded ${b}")
  endif()
endforeach()
