// SPDX-License-Identifier: Apache-2.0
#include "access.hpp"

#include <boost/asio/ip/address.hpp>

#include "sim/foxglove/protocol.hpp"

namespace sim::foxglove {
namespace {

// Origins of Foxglove's web app, which users point at ws://localhost:8765.
constexpr std::string_view kFoxgloveWebOrigins[] = {"https://app.foxglove.dev",
                                                    "https://studio.foxglove.dev"};

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

// "name:8765" -> "name", "[::1]:8765" -> "::1", "name" -> "name".
std::string_view host_name(std::string_view host) {
  if (!host.empty() && host.front() == '[') {
    const auto close = host.find(']');
    return close == std::string_view::npos ? host : host.substr(1, close - 1);
  }
  const auto colon = host.find(':');
  return colon == std::string_view::npos ? host : host.substr(0, colon);
}

// "https://viewer.example:8443/" -> "viewer.example".
std::string_view origin_host(std::string_view origin) {
  const auto scheme = origin.find("://");
  if (scheme == std::string_view::npos) return {};
  origin.remove_prefix(scheme + 3);
  return host_name(origin.substr(0, origin.find('/')));
}

bool is_ip_address(std::string_view name) {
  boost::system::error_code ec;
  (void)boost::asio::ip::make_address(std::string(name), ec);
  return !ec;
}

}  // namespace

std::optional<std::string_view> choose_subprotocol(const std::vector<std::string_view>& lines) {
  for (std::string_view list : lines) {
    while (!list.empty()) {
      const auto comma = list.find(',');
      const std::string_view item = trim(list.substr(0, comma));
      list = comma == std::string_view::npos ? std::string_view{} : list.substr(comma + 1);
      for (const std::string_view ours : kSubprotocols) {
        if (item == ours) return ours;
      }
    }
  }
  return std::nullopt;
}

AccessPolicy::AccessPolicy(std::vector<std::string> allowed_origins, std::string machine_name) {
  hosts_ = {"localhost"};
  if (!machine_name.empty()) {
    hosts_.push_back(lower(machine_name));
    hosts_.push_back(lower(machine_name) + ".local");
  }
  for (const std::string_view o : kFoxgloveWebOrigins) origins_.emplace_back(o);
  for (const std::string& o : allowed_origins) {
    if (o == "*") any_ = true;
    std::string origin = lower(trim(o));
    while (!origin.empty() && origin.back() == '/') origin.pop_back();
    if (const auto host = origin_host(origin); !host.empty()) hosts_.emplace_back(host);
    origins_.push_back(std::move(origin));
  }
}

std::string AccessPolicy::host_problem(std::string_view host) const {
  host = trim(host);
  if (any_ || host.empty()) return {};
  const std::string name = lower(host_name(host));
  if (is_ip_address(name)) return {};
  if (name.size() > 10 && name.ends_with(".localhost")) return {};
  for (const std::string& h : hosts_) {
    if (name == h) return {};
  }
  return "The host name " + name.substr(0, 100) +
         " is not this machine's (a page of another site may have pointed it here); open the "
         "page by IP address or localhost, or start sim_foxglove with --allow-origin "
         "http://" + name.substr(0, 100) + ":PORT to allow it.";
}

std::string AccessPolicy::origin_problem(std::string_view origin, std::string_view host) const {
  origin = trim(origin);
  if (any_ || origin.empty()) return {};
  std::string o = lower(origin);
  while (!o.empty() && o.back() == '/') o.pop_back();
  // A desktop app's "file://" has lost its slashes above (issue 32: it was never let in).
  if (o == "http://" + lower(trim(host)) || o == "file:") return {};
  for (const std::string& allowed : origins_) {
    if (o == allowed) return {};
  }
  return "Pages of " + o.substr(0, 100) +
         " may not read the streams; start sim_foxglove with --allow-origin " + o.substr(0, 100) +
         " to allow them.";
}

}  // namespace sim::foxglove
