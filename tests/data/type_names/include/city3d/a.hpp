// Fixture of Types.two_types_of_one_name_fail: Source is defined here and in src/b/b.cpp; the rest may stay.
#pragma once

namespace city3d {

struct Hidden;  // declared only: defined in src/a/a.cpp

class Source {
 public:
  struct Impl;
};

}  // namespace city3d
