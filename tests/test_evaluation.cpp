// placeholder until implemented
#include <gtest/gtest.h>
