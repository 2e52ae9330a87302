// SPDX-License-Identifier: Apache-2.0
// Everything a Hesai driver needs: models, calibration, packet view, frame assembler.
#pragma once

#include "sim/hesai/calibration.hpp"
#include "sim/hesai/frame_assembler.hpp"
#include "sim/hesai/model.hpp"
#include "sim/hesai/packet.hpp"
#include "sim/hesai/ptc.hpp"
#include "sim/hesai/ptc_time.hpp"
