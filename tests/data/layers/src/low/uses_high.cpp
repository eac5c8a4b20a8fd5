// An include that runs upward: the check must refuse it.
#include "city3d/low.hpp"
#include "high/thing.hpp"
