// The points-to-model distances (point_distances, the measure behind the RMSE, the rebuild check and
// the unsupported-surface measure) of every model in a folder of OBJ models against its cloud: the
// model `ID.obj` with the cloud `ID.ply` of the cloud folder (the models as `city3d reconstruct`
// writes them for single-building clouds, world coordinates). Both are moved by the same integer
// origin, as the pipeline's local frame does. Prints the models and points measured, the CPU of the
// distances (best of --runs runs) and a hash of their bits, so two builds can be compared: the same
// hash means the same distances to the last bit.
// Usage: bench_distances MODELS_DIR CLOUDS_DIR [--runs N]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/model_io.hpp"
#include "city3d/point_cloud_io.hpp"

namespace {

struct Case {
  city3d::PolygonMesh mesh;
  std::vector<city3d::Point3> points;
};

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (argc < 3) {
    std::fprintf(stderr, "usage: bench_distances MODELS_DIR CLOUDS_DIR [--runs N]\n");
    return 2;
  }
  int runs = 3;
  for (int i = 3; i + 1 < argc; i += 2)
    if (std::strcmp(argv[i], "--runs") == 0) runs = std::max(1, std::atoi(argv[i + 1]));
  std::vector<fs::path> models;
  for (const auto& e : fs::directory_iterator(argv[1]))
    if (e.is_regular_file() && e.path().extension() == ".obj") models.push_back(e.path());
  std::sort(models.begin(), models.end());
  std::vector<Case> cases;
  std::size_t points = 0;
  try {
    for (const fs::path& m : models) {
      const fs::path cloud = fs::path(argv[2]) / (m.stem().string() + ".ply");
      if (!fs::exists(cloud)) continue;
      Case c;
      c.mesh = city3d::read_obj_model(m.string()).mesh;
      c.points = city3d::read_point_cloud(cloud.string()).points;
      if (c.points.empty() || c.mesh.vertices.empty()) continue;
      const city3d::Point3 origin{std::round(c.points.front().x), std::round(c.points.front().y), 0.0};
      for (auto& v : c.mesh.vertices) v = {v.x - origin.x, v.y - origin.y, v.z};
      for (auto& p : c.points) p = {p.x - origin.x, p.y - origin.y, p.z};
      points += c.points.size();
      cases.push_back(std::move(c));
    }
  } catch (const city3d::Error& e) {
    std::fprintf(stderr, "bench_distances: %s\n", e.what());
    return 1;
  }
  double best = 1e300;
  std::uint64_t hash = 1469598103934665603ull;
  for (int run = 0; run < runs; ++run) {
    std::uint64_t h = 1469598103934665603ull;
    const double start = cpu_seconds();
    for (const Case& c : cases)
      for (const double d : city3d::point_distances(c.mesh, c.points)) {
        std::uint64_t bits = 0;
        std::memcpy(&bits, &d, sizeof bits);
        h = (h ^ bits) * 1099511628211ull;
      }
    best = std::min(best, cpu_seconds() - start);
    hash = h;
  }
  std::printf("%zu models, %zu points: distances %.3f s CPU (best of %d), hash %016llx\n", cases.size(),
              points, best, runs, static_cast<unsigned long long>(hash));
  return 0;
}
