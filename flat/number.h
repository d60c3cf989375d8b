// The one number syntax of kanesim: what a `.mech` file accepts as a number literal
// (docs/language.md "Lexical structure"), used by every option and file field that
// reads a number from text (command-line options, --grid values, list files, metric
// levels), so that a number means the same everywhere.
//
//   number  := digits [ '.' digits? ] [ exponent ]  |  '.' digits [ exponent ]
//   exponent := ( 'e' | 'E' ) [ '+' | '-' ] digits
//
// Outside a model a sign may lead (`-0.5`); in a model that sign is an operator. Not
// numbers: hexadecimal (`0x10`), `inf`, `nan`, digit separators, surrounding spaces.
// A value beyond the range of a double (`1e400`) or one that underflows to a subnormal
// (`1e-320`) is an error, as in a model.
#pragma once

#include <string>
#include <string_view>

namespace kanesim::flat {

// How numbers look, for hints.
inline constexpr const char* kNumberExamples = "3, -0.5, 1e-3 or 2.5E+4";

// Parses all of `text` as a number with an optional leading sign. False with the reason
// in *error otherwise ("'0x10' is not a number (numbers look like ...)", "'1e400' is out
// of range (beyond 1.8e308)").
bool ParseNumber(std::string_view text, double* value, std::string* error);

// An integer: optional sign, then digits only, within [lo, hi].
bool ParseInteger(std::string_view text, long long lo, long long hi, long long* value, std::string* error);

// The length of the longest prefix of `text` that is a number by the grammar above
// (no sign), 0 if none: the lexer's rule, exposed so that tests can hold the two equal.
size_t NumberPrefix(std::string_view text);

}  // namespace kanesim::flat
