// SPDX-License-Identifier: Apache-2.0
// Counts every operator new in the test binary (replacement in allocation_counter.cpp, its own
// translation unit so the compiler does not see the replacement inlined into callers).
#pragma once

#include <cstdint>

namespace unitree_test {
std::uint64_t allocations() noexcept;
}
