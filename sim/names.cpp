// SPDX-License-Identifier: Apache-2.0
#include "sim/names.hpp"

#include "region.hpp"

namespace sim {

std::string stream_name_problem(std::string_view name) { return detail::name_problem(name); }

}  // namespace sim
