// SurfaceInteraction's ray-origin rounding against the standard library.
#include <pbrt/interaction.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace pbrt;

TEST(SurfaceInteraction, NextFloatMatchesNextafter) {
    const Float big = std::numeric_limits<Float>::max(), tiny = std::numeric_limits<Float>::denorm_min();
    for (Float v : {0.f, -0.f, tiny, -tiny, 1.f, -1.f, 1e-30f, -3.5e7f, big, -big, Infinity, -Infinity,
                    std::numeric_limits<Float>::min(), 0.1f, -123.456f}) {
        Float up = SurfaceInteraction::NextFloatUp(v), down = SurfaceInteraction::NextFloatDown(v);
        Float refUp = std::nextafter(v, Infinity), refDown = std::nextafter(v, -Infinity);
        EXPECT_EQ(up, refUp) << v;
        EXPECT_EQ(std::signbit(up), std::signbit(refUp)) << v;
        EXPECT_EQ(down, refDown) << v;
        EXPECT_EQ(std::signbit(down), std::signbit(refDown)) << v;
    }
    EXPECT_TRUE(std::isnan(SurfaceInteraction::NextFloatUp(NAN)));
}
