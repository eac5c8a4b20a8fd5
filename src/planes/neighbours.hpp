// The k nearest neighbours of every point of a building, as CGAL's kd-tree search gives them
// (planes.cpp's one neighbour structure for the normals, the seed order, the growing and the refit).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "city3d/types.hpp"

namespace city3d::detail {

/// How the lists were found (for the tests and benchmarks).
struct NeighbourStats {
  std::size_t from_grid = 0;  ///< lists the grid search settled
  std::size_t from_tree = 0;  ///< lists handed to CGAL's kd-tree (a tie, a near tie, or too few points)
};

/// For each of `points` (no two equal, fewer than 2^32), the indices of its min(k, n) nearest points, nearest
/// first and itself among them: point i's at [i * min(k, n), (i + 1) * min(k, n)). The lists are those of
/// CGAL's Shape_detection::Point_set::K_neighbor_query (an Orthogonal_k_neighbor_search on a sliding-midpoint
/// kd-tree, exact, sorted), entry for entry.
///
/// A grid over x and y answers first: it finds the k + 1 nearest by the same squared distance, in
/// the same arithmetic as CGAL's Euclidean_distance, so when those k + 1 distances are distinct its
/// sorted list is the only one an exact search can give. Where two of them are equal, the tree's
/// traversal decides the order or the membership, and where the k-th and (k+1)-th differ by less
/// than a relative 1e-9 the tree's rounded pruning could, in principle, decide it: such points, and
/// every point of a set of at most k + 1, are searched with CGAL's own K_neighbor_query instead.
std::vector<std::uint32_t> k_nearest_lists(const std::vector<Point3>& points, std::size_t k,
                                           NeighbourStats* stats = nullptr);

}  // namespace city3d::detail
