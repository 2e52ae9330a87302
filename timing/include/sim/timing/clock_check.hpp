// SPDX-License-Identifier: Apache-2.0
#pragma once
#include "sim/clock_status.hpp"
