// The layer batch/ (kanesim_batch): many runs of one model — sweeps (grids, lists, random
// and Latin-hypercube samples; threads, worker processes or MPI) with their summaries, and
// golden-output regression tests — and the guards of every file kanesim writes. Layers
// above include this header or the parts it lists.
#pragma once

#include "batch/csv_util.h"         // CSV quoting shared by summaries and golden files
#include "batch/file_guard.h"       // atomic replacement, locks, refusing special files
#include "batch/golden.h"           // `kanesim test`: golden-output regression tests
#include "batch/metrics.h"          // scalar metrics of a scenario's signals
#include "batch/scenario.h"         // where scenarios come from
#include "batch/settings_record.h"  // what a sweep summary was made with
#include "batch/summary.h"          // the sweep summary file
#include "batch/sweep.h"            // `kanesim sweep`
#include "batch/sweep_toml.h"       // sweep.toml
#include "batch/worker_pool.h"      // scenarios in worker processes
