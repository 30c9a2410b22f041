#include <gtest/gtest.h>
TEST(Types, Placeholder) { EXPECT_EQ(1, 1); }
