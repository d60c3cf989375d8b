// The layer flat/ (kanesim_flat): the flat mechanism, the one representation between the
// language (which writes it) and the compiler (which reads it), with no language left in it
// and no dependency. Layers above include this header or the parts it lists.
#pragma once

#include "flat/diagnostic_codes.h"  // the one table of diagnostic codes (language and compiler)
#include "flat/expr.h"              // scalar expressions: a pool of nodes, built and evaluated
#include "flat/file_name.h"         // source file names as the locations keep them
#include "flat/mechanism.h"         // the flat mechanism: parameters, frames, bodies, joints, forces
#include "flat/number.h"            // the one number syntax (literals, --set values)
#include "flat/param_eval.h"        // values of parameter expressions
#include "flat/union_find.h"        // disjoint sets (frames joined by connections, rigid groups)
