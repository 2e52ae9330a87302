// SPDX-License-Identifier: Apache-2.0
// Everything a C++ program needs to write or read SIM streams. C++17 or later (sim::span is
// std::span under C++20).
#pragma once

#include "sim/clock.hpp"
#include "sim/layout.hpp"
#include "sim/lidar_point.hpp"
#include "sim/names.hpp"
#include "sim/os.hpp"
#include "sim/pairing.hpp"
#include "sim/reader.hpp"
#include "sim/result.hpp"
#include "sim/sensor_info.hpp"
#include "sim/span.hpp"
#include "sim/wait_set.hpp"
#include "sim/writer.hpp"
