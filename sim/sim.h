// The layer sim/ (kanesim_sim): time integration of a compiled Program, seen through the
// runtime's public face only (runtime/runtime.h) — DOP853 and SUNDIALS' CVODE, IDA and
// ARKODE — and the outputs: signal selection, CSV rows, the energy guard. Layers above
// include this header or the parts it lists.
#pragma once

#include "sim/csv.h"            // signal rows and the CSV writer
#include "sim/diagonal_speeds.h"  // Lesser's diagonal generalized speeds (--speeds diagonal)
#include "sim/energy_guard.h"   // stopping a conservative model whose energy drifts
#include "sim/integrator.h"     // the integrators, generic over the right-hand side
#include "sim/signal_select.h"  // --output patterns over signal names
#include "sim/input_table.h"    // the model's inputs: tables (--input-file) and constants
#include "sim/sensitivity.h"    // a run with d(y)/d(p) by the variational equations
#include "sim/simulate.h"       // one run of a Program from start to stop
#include "sim/simulator.h"      // the stepping core: a Program advanced step by step
#include "sim/hybrid_ode.h"     // the equations with their events, for an outside integrator

// The hybrid laws, for linearize's operating points (linearize/hybrid.h):
// kanesim-public: sim/end_stops.h
// kanesim-public: sim/stick_slip.h
// kanesim-public: sim/lift_off.h
