#include "city3d/a.hpp"

namespace city3d {
namespace {

struct Helper {  // private to this file, as is b.cpp's
  int x = 0;
};

}  // namespace

struct Hidden {
  int y = 0;
};

struct Source::Impl {  // a member of Source, not a second Source
  int z = 0;
};

}  // namespace city3d
