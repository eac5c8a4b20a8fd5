// The advice of a run's summary: when most rows share one problem, a line naming it and its likely
// fix, from the classes the tiles hold and the run's options (BatchSummary::advice).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "city3d/run_outputs.hpp"

namespace city3d::detail {

/// The classes of the tiles' points, each tile counted once, as the crop streamed them: what the
/// advice of a run without building points names.
struct ClassCounts {
  std::vector<bool> counted;            ///< per tile
  bool any = false;                     ///< some tile had classes
  std::array<std::uint64_t, 256> n{};   ///< points per class
};

/// The classes `classes` counted, each with its name and count: "1 (unclassified, 282,445), 2 (ground, ...)".
std::string classes_present(const ClassCounts& classes);

/// One line naming the problem most rows share (BatchSummary::main_problem) and its likely fix, from
/// what the run knows: the classes its tiles hold (`classes`, when it streamed any with classes) and
/// its options (`building_classes`: --building-classes as given; empty for a merge). Empty without a
/// main problem.
std::string advice_for(const BatchSummary& s, const ClassCounts* classes, const std::string& building_classes);

}  // namespace city3d::detail
