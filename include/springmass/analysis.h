// springmass: static equilibrium and natural frequencies (GSL).
#pragma once

#include "springmass/model.h"
