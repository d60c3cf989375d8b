// The layer lang/ (kanesim_lang): .mech text in, a flat mechanism (flat/flat.h) out —
// lexer, parser, abstract syntax tree, diagnostics, and the elaborator (lookup, modifiers,
// instantiation, evaluation, connections, emission). Layers above include this header or
// the parts it lists.
#pragma once

#include "lang/ast.h"           // the abstract syntax tree of a .mech file
#include "lang/diagnostics.h"   // diagnostics: code, span, notes, hint, and their rendering
#include "lang/elaborate.h"     // parsed files -> the flat mechanism
#include "lang/node_pool.h"     // the syntax tree's node pools, and their lock around a fork
#include "lang/parser.h"        // .mech text -> syntax tree
#include "lang/set_argument.h"  // a --set NAME=VALUE argument as typed
#include "lang/text.h"          // source text as characters, made safe to print
#include "lang/units.h"         // unit strings ("N.m/rad") as SI exponents and a scale
