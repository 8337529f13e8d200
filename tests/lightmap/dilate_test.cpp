// Dilation: padding texels take their covered neighbours' values ring by ring.
#include "lightmap/dilate.h"

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
