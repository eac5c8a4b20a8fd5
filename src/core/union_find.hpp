// Union-find over 0 .. n-1 with path halving: faces, corners, pixels or points joined into parts.
// Private to the library; the one copy every module uses.
#pragma once

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

namespace city3d::detail {

class UnionFind {
 public:
  explicit UnionFind(std::size_t n = 0) { reset(n); }
  /// Starts again over 0 .. n-1, each element a part of its own (the storage is kept).
  void reset(std::size_t n) {
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), std::size_t{0});
  }
  /// The root of i's part: i itself for the one root of each part.
  std::size_t find(std::size_t i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  /// Joins a's part to b's: b's root is the root of both.
  void join(std::size_t a, std::size_t b) {
    const std::size_t root = find(b);
    parent_[find(a)] = root;
  }
  /// Joins the parts of a and b under the smaller of their roots, so that a part's root is its
  /// smallest member.
  void join_to_smaller(std::size_t a, std::size_t b) {
    const std::size_t ra = find(a), rb = find(b);
    if (ra != rb) parent_[std::max(ra, rb)] = std::min(ra, rb);
  }

 private:
  std::vector<std::size_t> parent_;
};

}  // namespace city3d::detail
