// A stage reaching up to a later stage and to an application: what the include rules refuse.
#pragma once
#include "cone/radiance_mips.h"
#include "gather/irradiance_cache.h"
#include "bench/run.h"
