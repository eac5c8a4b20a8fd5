// A private header of the higher module.
#pragma once
#include "city3d/high.hpp"
