#include <gtest/gtest.h>
TEST(AllocFree, Placeholder) {}
