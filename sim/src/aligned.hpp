// The allocator lives with the public headers (State's particle arrays use it).
#pragma once

#include "pmfrag/aligned.hpp"
