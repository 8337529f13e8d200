// The GPU layer reaching into the job: what the include rules refuse.
#include "gather/shade_element.h"
#include "bake/bake.h"
