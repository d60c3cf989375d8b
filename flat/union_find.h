// Disjoint sets over 0 .. n-1 with path halving: frames joined by connections (the
// elaborator), subtrees joined by forces (the runtime's coupling groups).
#pragma once

#include <cstddef>
#include <numeric>
#include <utility>
#include <vector>

namespace kanesim::flat {

class UnionFind {
 public:
  explicit UnionFind(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  int Find(int x) {
    while (parent_[static_cast<std::size_t>(x)] != x) {
      parent_[static_cast<std::size_t>(x)] = parent_[static_cast<std::size_t>(parent_[static_cast<std::size_t>(x)])];
      x = parent_[static_cast<std::size_t>(x)];
    }
    return x;
  }
  // Joins the sets of a and b and returns the root: the smaller of the two roots, so the
  // earliest-declared member names a set.
  int Unite(int a, int b) {
    a = Find(a);
    b = Find(b);
    if (b < a) std::swap(a, b);
    parent_[static_cast<std::size_t>(b)] = a;
    return a;
  }

 private:
  std::vector<int> parent_;
};

}  // namespace kanesim::flat
