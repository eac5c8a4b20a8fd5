// Validates every OBJ model in the given folders (or files) with city3d's val3dity-equivalent check,
// each edge-connected part as one solid (as the CityJSON writer writes it), on the coordinates as
// written in the file. Prints the number of models, how many are valid, the count per error code and
// every invalid model with its errors. Exit status 1 when any model is invalid.
// Usage: bench_validity DIR_OR_OBJ...
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/model_io.hpp"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    if (fs::is_directory(argv[i])) {
      for (const auto& e : fs::recursive_directory_iterator(argv[i]))
        if (e.is_regular_file() && e.path().extension() == ".obj") files.push_back(e.path().string());
    } else {
      files.push_back(argv[i]);
    }
  }
  std::sort(files.begin(), files.end());
  std::size_t valid = 0;
  std::map<int, std::size_t> per_code;
  for (const std::string& f : files) {
    try {
      const city3d::BuildingModel model = city3d::read_obj_model(f);
      const auto errors = city3d::validate_model(model.mesh);
      if (errors.empty()) {
        ++valid;
        continue;
      }
      std::map<int, bool> seen;
      for (const auto& e : errors)
        if (!seen[e.code]) ++per_code[e.code], seen[e.code] = true;
      std::printf("invalid %s: %s\n", f.c_str(), errors.front().text().c_str());
    } catch (const city3d::Error& e) {
      std::printf("unreadable %s: %s\n", f.c_str(), e.what());
    }
  }
  std::printf("%zu models, %zu valid, %zu invalid\n", files.size(), valid, files.size() - valid);
  for (const auto& [code, n] : per_code) std::printf("  %d %s: %zu models\n", code, city3d::validity_error_name(code), n);
  return valid == files.size() ? 0 : 1;
}
