// A cropping pass of the batch: the point-cloud tiles streamed into the cropper, only where the pass's
// blocks need points.
#pragma once

#include <string>
#include <vector>

#include "batch/advice.hpp"
#include "city3d/crop.hpp"
#include "city3d/point_cloud_io.hpp"
#include "city3d/types.hpp"

namespace city3d::detail {

// Streams every tile that overlaps one of `regions` (the blocks' footprints and their ground buffers)
// into the cropper. A tile whose header has no bounds (PLY) gets them from its points, in `bounds`; a tile
// streamed the first time adds its classes to `classes`.
// `extents` (one per file, kept from pass to pass): where the chunks of each LAZ tile lie, learnt in
// the first pass that reads the tile; later passes decode only the chunks that meet their regions
// (the cropper takes nothing from the points outside them, as it takes nothing from a tile outside
// them).
void crop_tiles(const std::vector<std::string>& files, const std::vector<Box2>& regions, unsigned threads,
                Cropper& cropper, std::vector<Box3>& bounds, ClassCounts& classes,
                std::vector<ChunkExtents>& extents);

}  // namespace city3d::detail
