// SPDX-License-Identifier: Apache-2.0
#include "sim/timing/clock_check.hpp"
