// springmass: spring-mass-damper systems in C. Include this header for the whole public API.
#pragma once

#include "springmass/analysis.h"
#include "springmass/base.h"
#include "springmass/model.h"
#include "springmass/model_file.h"
#include "springmass/simulation.h"
#include "springmass/structures.h"
