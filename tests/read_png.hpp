// Reads a PNG's pixels for the tests, through GDAL's PNG driver (the library's own file-format
// dependency): width, height, bands and the 8-bit samples interleaved by pixel, rows from the top.
#pragma once

#include <cpl_error.h>
#include <gdal.h>

#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

namespace city3d::test {

struct PngPixels {
  int width = 0, height = 0, bands = 0;
  std::vector<std::uint8_t> samples;  // empty when the file could not be read
  std::uint8_t at(int x, int y, int band) const {
    return samples[(static_cast<std::size_t>(y) * width + x) * bands + band];
  }
};

inline PngPixels read_png(const std::string& path) {
  static std::once_flag registered;
  std::call_once(registered, [] { GDALAllRegister(); });
  PngPixels png;
  CPLPushErrorHandler(CPLQuietErrorHandler);
  const char* const png_only[] = {"PNG", nullptr};
  const GDALDatasetH data =
      GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, png_only, nullptr, nullptr);
  CPLPopErrorHandler();
  if (!data) return png;
  png.width = GDALGetRasterXSize(data);
  png.height = GDALGetRasterYSize(data);
  png.bands = GDALGetRasterCount(data);
  std::vector<std::uint8_t> samples(static_cast<std::size_t>(png.width) * png.height * png.bands);
  if (GDALDatasetRasterIO(data, GF_Read, 0, 0, png.width, png.height, samples.data(), png.width, png.height,
                          GDT_Byte, png.bands, nullptr, png.bands, png.bands * png.width, 1) == CE_None)
    png.samples = std::move(samples);
  GDALClose(data);
  return png;
}

}  // namespace city3d::test
