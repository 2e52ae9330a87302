// SPDX-License-Identifier: Apache-2.0
#include "sim/timing/host_clock.hpp"
