// The gather's settings as flags and job-file keys: ranges refused by name.
#include "bake/bake_settings.h"
#include "core/error.h"

#include <catch2/catch.hpp>

using namespace vl;

TEST_CASE("Gather visibility and ray counts outside their ranges are refused by name", "[bake]") {
    BakeSettings settings;
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "gather-visibility", "sideways"),
                      Catch::Contains("gather-visibility") && Catch::Contains("auto, cones, rays"));
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "gather-rays", "0"), Catch::Contains("gather-rays"));
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "bounce-rays", "65"), Catch::Contains("bounce-rays"));
    settings.gather.bounceRays = 0;
    CHECK_THROWS_WITH(validateBakeSettings(settings), Catch::Contains("bounce-rays"));
    applySetting(bakeSettingsTable(), settings, "gather-visibility", "cones");
    CHECK(settings.gather.visibility == GatherVisibility::Cones);
}
