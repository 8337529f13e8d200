// Includes of the stages gather builds on, and a third-party header: none is refused.
#pragma once
#include "cone/radiance_mips.h"
#include "receivers/receivers.h"
#include "nanovdb/NanoVDB.h"
