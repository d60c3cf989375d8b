// Which cases of a grid the slowest tests run under the sanitizers. Under AddressSanitizer +
// UndefinedBehaviorSanitizer (CI's build-asan, -O1) a run takes 30-100x its Release time, and
// the sanitizer stage checks memory and undefined behaviour, not the physics again: there
// those tests run a cross-section of their cases that still takes every row and every
// column of the grid (every integrator, every model variant) at least once, each case with
// its full assertions. The Release build runs every case.
#pragma once

#include <cstddef>
#include <initializer_list>
#include <set>
#include <string>

namespace kanesim::test {

#if defined(__SANITIZE_ADDRESS__) || defined(KANESIM_STRESS_SHORT)
inline constexpr bool kUnderSanitizers = true;
#else
inline constexpr bool kUnderSanitizers = false;
#endif

// Whether case (a, b) of an na x nb grid runs: every case in Release; under the sanitizers
// max(na, nb) cases on a wrapped diagonal, so each a and each b runs once or more.
inline bool RunsCase(std::size_t a, std::size_t na, std::size_t b, std::size_t nb) {
  if (!kUnderSanitizers) return true;
  return na >= nb ? b == a % nb : a == b % na;
}

// For a list of cases each of several kinds (an integrator, a solver path): every case in
// Release; under the sanitizers a case runs when one of its kinds has not run yet, so each
// integrator and each path runs once or more.
class FirstOfEachKind {
 public:
  bool Runs(std::initializer_list<std::string> kinds) {
    bool fresh = !kUnderSanitizers;
    for (const std::string& k : kinds) fresh = seen_.insert(k).second || fresh;
    return fresh;
  }

 private:
  std::set<std::string> seen_;
};

}  // namespace kanesim::test
