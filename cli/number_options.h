// Numeric command-line options read with the language's number syntax
// (flat/number.h), so that `--stop-time 0x10`, `inf`, `nan` or `1e400` are refused
// with the reason, as they would be in a model (CLI11's own conversion takes all four).
// A refused value is a usage error: CLI11 prints "--name: <why>" and main exits with 1.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "flat/number.h"

namespace kanesim::cli {

// A real number into *target; count() > 0 when given.
inline CLI::Option* AddNumberOption(CLI::App* app, const std::string& name, double* target, const std::string& help) {
  const std::string flag = name.substr(0, name.find(','));
  return app
      ->add_option_function<std::string>(
          name,
          [target, flag](const std::string& text) {
            std::string why;
            if (!flat::ParseNumber(text, target, &why))
              throw CLI::ValidationError(flag, why);
          },
          help)
      ->type_name("NUMBER");
}

// An integer in [lo, hi] into *target.
template <typename Int>
CLI::Option* AddIntegerOption(CLI::App* app, const std::string& name, Int* target, long long lo, long long hi,
                              const std::string& help) {
  const std::string flag = name.substr(0, name.find(','));
  return app
      ->add_option_function<std::string>(
          name,
          [target, flag, lo, hi](const std::string& text) {
            std::string why;
            long long v = 0;
            if (!flat::ParseInteger(text, lo, hi, &v, &why)) throw CLI::ValidationError(flag, why);
            *target = static_cast<Int>(v);
          },
          help)
      ->type_name("INT");
}

}  // namespace kanesim::cli
