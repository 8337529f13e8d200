// Dilation: padding texels take their covered neighbours' values ring by ring.
#include "lightmap/dilate.h"
#include "scene/scene.h"

#include <catch2/catch.hpp>

using namespace vl;

TEST_CASE("Dilation fills padding ring by ring from covered neighbours and keeps covered texels", "[bake]") {
    Image image(5, 1, 1, 0.0f), mask(5, 1, 1, 0.0f);
    image.at(1, 0) = 2.0f;
    image.at(3, 0) = 4.0f;
    mask.at(1, 0) = mask.at(3, 0) = 1.0f;
    image.at(0, 0) = 99.0f;  // padding content is replaced
    REQUIRE(dilatePadding(image, mask) == 3);
    REQUIRE(image.at(0, 0) == 2.0f);
    REQUIRE(image.at(2, 0) == 3.0f);  // mean of both neighbours
    REQUIRE(image.at(4, 0) == 4.0f);
    REQUIRE(image.at(1, 0) == 2.0f);
    Image wide(6, 1, 1, 0.0f), wideMask(6, 1, 1, 0.0f);
    wide.at(0, 0) = 1.0f;
    wideMask.at(0, 0) = 1.0f;
    REQUIRE(dilatePadding(wide, wideMask, 2) == 2);  // two passes reach two texels
    REQUIRE(wide.at(2, 0) == 1.0f);
    REQUIRE(wide.at(3, 0) == 0.0f);
}

TEST_CASE("A shadowmask's unseen texels and padding take their neighbours' values, channel by channel",
          "[bake]") {
    // A 3 × 1 strip, all covered: texel 0 holds 0.2 in channel 0, texel 2 holds 0.8, and texel 1
    // faces no light in channel 0 (unseen); channel 1 faces its light nowhere. A fourth texel,
    // padding, sits past texel 2 (a 4 × 1 image).
    Image mask(4, 1, 1, 1.0f);
    mask.at(3, 0) = 0.0f;
    Image shadowmask(4, 1, kShadowmaskChannels, 1.0f);
    const float channel0[] = {0.2f, kShadowmaskUnseen, 0.8f, 0.0f};
    for (int x = 0; x < 4; ++x) {
        shadowmask.at(x, 0, 0) = channel0[x];
        shadowmask.at(x, 0, 1) = kShadowmaskUnseen;
    }
    fillUnseenShadowmask(shadowmask, mask);
    CHECK(shadowmask.at(0, 0, 0) == 0.2f);  // seen texels keep their values
    CHECK(shadowmask.at(2, 0, 0) == 0.8f);
    CHECK(shadowmask.at(1, 0, 0) == Approx(0.5f));  // the mean of its seen neighbours, not 0
    CHECK(shadowmask.at(3, 0, 0) == 0.8f);           // padding: its one filled neighbour
    for (int x = 0; x < 4; ++x) CHECK(shadowmask.at(x, 0, 1) == 1.0f);  // nothing faces its light
    for (int x = 0; x < 4; ++x) CHECK(shadowmask.at(x, 0, 2) == 1.0f);  // unused channels stay 1
}
