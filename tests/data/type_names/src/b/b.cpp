namespace city3d::detail {
namespace {

struct Helper {
  double x = 0.0;
};

}  // namespace

struct Source {  // a second Source: refused
  const char* name = nullptr;
};

}  // namespace city3d::detail
