// The higher module.
#pragma once
#include "city3d/low.hpp"
