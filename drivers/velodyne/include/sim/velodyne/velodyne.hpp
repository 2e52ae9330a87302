// SPDX-License-Identifier: Apache-2.0
// Everything a Velodyne driver needs: models, packets, calibration, frame assembler.
#pragma once

#include "sim/velodyne/calibration.hpp"
#include "sim/velodyne/frame_assembler.hpp"
#include "sim/velodyne/model.hpp"
#include "sim/velodyne/packet.hpp"
#include "sim/velodyne/position_clock.hpp"
