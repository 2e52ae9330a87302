// SPDX-License-Identifier: Apache-2.0
// Everything an Ouster driver needs: metadata, packet view, frame assembler.
#pragma once

#include "sim/ouster/frame_assembler.hpp"
#include "sim/ouster/metadata.hpp"
#include "sim/ouster/packet.hpp"
#include "sim/ouster/time_status.hpp"
