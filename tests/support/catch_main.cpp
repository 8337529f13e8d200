#define CATCH_CONFIG_MAIN
// Wide enough that a skipped test's reason stays on one line for tools/setup-and-test.sh.
#define CATCH_CONFIG_CONSOLE_WIDTH 300
#include <catch2/catch.hpp>
