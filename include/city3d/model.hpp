// Model assembly (paper section 3.3, last step): the selected candidate faces welded into one compact,
// closed, 2-manifold, outward-oriented polygon mesh.
#pragma once

#include <vector>

#include "city3d/hypothesis.hpp"
#include "city3d/types.hpp"

namespace city3d {

/// Parameters of assemble_model(). Distances in metres.
struct AssembleParams {
  /// A vertex whose distance from the line through its two neighbours is below this is collinear
  /// (removable when no other face uses it). > 0.
  double collinear_tolerance = 1e-3;
  /// Merge adjacent selected faces of the same plane into one polygon (the compact model).
  bool merge_coplanar = true;
  /// A merged polygon with a vertex farther than this from its plane is left as its pieces: walls
  /// on one line of the arrangement can bend by the centimetre that contracting a short edge moves
  /// a vertex. > 0.
  double planarity_tolerance = 2e-3;

  /// Throws ConfigError listing every invalid field.
  void validate() const;
};

/// Assembles the faces with selected[i] == true (one flag per candidate face).
///
/// Steps: (1) weld: faces share vertices by identity (CandidateFaces::vertices), never by
/// coordinates; every undirected edge must be used by exactly two selected faces; (2) orient: faces
/// are made consistent by a breadth-first walk over shared edges, then each shell is flipped when its
/// signed volume is negative; (3) merge: adjacent faces with the same plane_id become one polygon (the
/// edges between them cancel); a merged region whose boundary is not one simple loop (a hole, or two
/// loops touching at a vertex) is left as its original faces, which are simple; (4) clean: a vertex
/// that only two faces share, with exactly two neighbours, and that is collinear with them is removed
/// from both faces (vertices used by a third face stay, so there are no T-junctions); (5) validate
/// with check_mesh().
///
/// `surfaces`, when not null, receives one SurfaceType per output face (roof, wall, ground).
/// Throws ConfigError (params, or selected.size() != face count) and ReconstructionError naming the
/// failure ("model: edge 12-40 is used by 3 selected faces", "model: not closed: 4 boundary edges",
/// "model: volume -3.2 m3 <= 0", ...): the pipeline then falls back to a simpler model.
PolygonMesh assemble_model(const CandidateFaces& candidates, const std::vector<bool>& selected,
                           const AssembleParams& params, std::vector<SurfaceType>* surfaces = nullptr);

}  // namespace city3d
