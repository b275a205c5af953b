#include <gtest/gtest.h>
#include "lib/so3.hpp"
TEST(So3, Placeholder) { EXPECT_TRUE(liedyn::so3::exp(Eigen::Vector3d::Zero()).isIdentity()); }
