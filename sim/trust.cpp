// SPDX-License-Identifier: Apache-2.0
// Whose regions a reader accepts (sim::Trust), and the user and group names its sentences use.
#include <grp.h>
#include <pwd.h>
#include <unistd.h>

#include <charconv>
#include <string>

#include "region.hpp"
#include "sim/reader.hpp"

namespace sim {

namespace detail {

std::string user_name(uid_t uid) {
  char buffer[1024];
  passwd entry{};
  passwd* found = nullptr;
  if (getpwuid_r(uid, &entry, buffer, sizeof buffer, &found) == 0 && found != nullptr) {
    return std::string(found->pw_name) + " (uid " + std::to_string(uid) + ")";
  }
  return "uid " + std::to_string(uid);
}

std::string group_name(gid_t gid) {
  char buffer[1024];
  group entry{};
  group* found = nullptr;
  if (getgrgid_r(gid, &entry, buffer, sizeof buffer, &found) == 0 && found != nullptr) {
    return std::string(found->gr_name) + " (gid " + std::to_string(gid) + ")";
  }
  return "gid " + std::to_string(gid);
}

}  // namespace detail

namespace {

// A whole decimal number, or nothing.
std::optional<std::uint32_t> numeric_id(std::string_view text) {
  std::uint32_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc{} || end != text.data() + text.size()) return std::nullopt;
  return value;
}

}  // namespace

Expected<Trust> Trust::parse(std::string_view owner, std::string_view group_text) {
  Trust trust;
  char buffer[4096];
  if (!owner.empty()) {
    if (auto id = numeric_id(owner)) {
      trust.owner_uid = *id;
    } else {
      const std::string name(owner);
      passwd entry{};
      passwd* found = nullptr;
      if (getpwnam_r(name.c_str(), &entry, buffer, sizeof buffer, &found) != 0 || found == nullptr) {
        return Error{ErrorCode::invalid_argument,
                     "there is no user named \"" + detail::printable(owner) +
                         "\" on this machine; give an existing user name or a numeric uid"};
      }
      trust.owner_uid = found->pw_uid;
    }
  }
  if (!group_text.empty()) {
    if (auto id = numeric_id(group_text)) {
      trust.group_gid = *id;
    } else {
      const std::string name(group_text);
      ::group entry{};
      ::group* found = nullptr;
      if (getgrnam_r(name.c_str(), &entry, buffer, sizeof buffer, &found) != 0 || found == nullptr) {
        return Error{ErrorCode::invalid_argument,
                     "there is no group named \"" + detail::printable(group_text) +
                         "\" on this machine; give an existing group name or a numeric gid"};
      }
      trust.group_gid = found->gr_gid;
    }
  }
  return trust;
}

std::string Trust::describe() const {
  if (anyone) return "any user";
  if (!owner_uid && !group_gid) return "this user, " + detail::user_name(geteuid());
  std::string text;
  if (owner_uid) text = "user " + detail::user_name(*owner_uid);
  if (group_gid) text += (text.empty() ? "group " : " and group ") + detail::group_name(*group_gid);
  return text;
}

}  // namespace sim
