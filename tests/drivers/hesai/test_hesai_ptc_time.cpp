// SPDX-License-Identifier: Apache-2.0
// The PTC clock answers (0x06 queries 1–4, 0x09, 0x26) on crafted bytes, laid out here from
// the documented layouts (big-endian): each field where the layout puts it, answers cut short
// refused in one sentence, and the ClockStatus they make (source, state, domain, offset, path
// delay, grandmaster, UTC offset) whatever the values.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "sim/hesai/ptc_time.hpp"

namespace {

using namespace sim::hesai;
using Bytes = std::vector<std::uint8_t>;

void put(Bytes& b, std::uint64_t value, std::size_t size) {
  for (std::size_t i = 0; i < size; ++i) b.push_back(static_cast<std::uint8_t>(value >> (8 * (size - 1 - i))));
}

const Bytes own{0xbc, 0x0f, 0xa7, 0xff, 0xfe, 0x12, 0x34, 0x56};
const Bytes gm{0x00, 0x17, 0x47, 0xff, 0xfe, 0x70, 0x00, 0x38};

Bytes ptp_status(std::int64_t offset) {
  Bytes b;
  put(b, static_cast<std::uint64_t>(offset), 8);
  put(b, 3, 4);
  put(b, 1000, 4);
  return b;
}

Bytes port_data_set(std::uint8_t state, const Bytes& clock, std::uint8_t delay_mechanism, std::int64_t delay_ns) {
  Bytes b(clock);
  put(b, 1, 2);
  b.push_back(state);
  b.push_back(0);
  put(b, static_cast<std::uint64_t>(delay_ns) << 16, 8);
  for (int v : {1, 3, 0}) b.push_back(static_cast<std::uint8_t>(v));
  b.push_back(delay_mechanism);
  b.push_back(0);
  b.push_back(2);
  return b;
}

Bytes time_status_np(std::int64_t offset, bool present, const Bytes& identity) {
  Bytes b;
  put(b, static_cast<std::uint64_t>(offset), 8);
  put(b, 1'700'000'000'000'000'000ULL, 8);
  b.resize(38, 0);
  put(b, present ? 1 : 0, 4);
  b.insert(b.end(), identity.begin(), identity.end());
  return b;
}

Bytes grandmaster_settings(std::int16_t utc_offset, std::uint8_t flags) {
  Bytes b{6, 0x21};
  put(b, 0x4E5D, 2);
  put(b, static_cast<std::uint16_t>(utc_offset), 2);
  b.push_back(flags);
  b.push_back(0xA0);
  return b;
}

Bytes lidar_status(bool qt, std::uint8_t ptp, bool pps, bool gprmc) {
  Bytes b(qt ? 58 : 54, 0);
  if (qt) {
    b[52] = ptp;
  } else {
    b[38] = pps;
    b[39] = gprmc;
    b[48] = ptp;
  }
  return b;
}

// The value of an answer the test built whole.
template <class T>
T got(sim::Expected<T> parsed) {
  EXPECT_TRUE(parsed) << parsed.error().message;
  return parsed ? parsed.value() : T{};
}

}  // namespace

TEST(HesaiPtcTime, ARequestWithAPayloadAnnouncesItsLength) {
  const std::uint8_t query[] = {3};
  EXPECT_EQ(ptc::request(0x06, query), (Bytes{0x47, 0x74, 0x06, 0x00, 0x00, 0x00, 0x00, 0x01, 0x03}));
  EXPECT_EQ(ptc::request(0x26, {}), (Bytes{0x47, 0x74, 0x26, 0, 0, 0, 0, 0}));
}

TEST(HesaiPtcTime, EachAnswerIsReadFromWhereItsLayoutPutsItsFields) {
  auto status = ptc::parse_ptp_status(ptp_status(-123456789));
  ASSERT_TRUE(status) << status.error().message;
  EXPECT_EQ(status->master_offset_ns, -123456789);
  EXPECT_EQ(status->ptp_state, 3);
  EXPECT_EQ(status->elapsed_ms, 1000);

  auto port = ptc::parse_port_data_set(port_data_set(9, own, 2, 850));
  ASSERT_TRUE(port) << port.error().message;
  EXPECT_EQ(ptc::clock_identity_text(port->clock), "bc0fa7.fffe.123456");
  EXPECT_EQ(port->port_number, 1);
  EXPECT_EQ(port->port_state, 9);
  EXPECT_EQ(port->peer_mean_path_delay_ns, 850);
  EXPECT_EQ(port->delay_mechanism, 2);
  EXPECT_EQ(port->version, 2);

  auto time = ptc::parse_time_status_np(time_status_np(42, true, gm));
  ASSERT_TRUE(time) << time.error().message;
  EXPECT_EQ(time->master_offset_ns, 42);
  EXPECT_EQ(time->ingress_time_ns, 1'700'000'000'000'000'000);
  EXPECT_TRUE(time->gm_present);
  EXPECT_EQ(ptc::clock_identity_text(time->gm_identity), "001747.fffe.700038");

  auto settings = ptc::parse_grandmaster_settings_np(grandmaster_settings(37, 0x0C));
  ASSERT_TRUE(settings) << settings.error().message;
  EXPECT_EQ(settings->clock_class, 6);
  EXPECT_EQ(settings->utc_offset_s, 37);
  EXPECT_TRUE(settings->utc_offset_valid());
  EXPECT_TRUE(settings->ptp_timescale());

  auto xt = ptc::parse_lidar_status(lidar_status(false, 2, true, false), ptc::StatusLayout::xt);
  ASSERT_TRUE(xt);
  EXPECT_EQ(xt->ptp_status, 2);
  EXPECT_EQ(xt->gps_pps_locked, true);
  EXPECT_EQ(xt->gps_gprmc_locked, false);
  auto qt = ptc::parse_lidar_status(lidar_status(true, 1, false, false), std::nullopt);  // by its size
  ASSERT_TRUE(qt);
  EXPECT_EQ(qt->ptp_status, 1);
  EXPECT_FALSE(qt->gps_pps_locked.has_value());
  EXPECT_EQ(ptc::status_layout(Model::pandar_qt128), ptc::StatusLayout::qt);
  EXPECT_EQ(ptc::status_layout(Model::pandar64), ptc::StatusLayout::xt);

  auto config = ptc::parse_ptp_config(Bytes{1, 1, 24, 1, 0, 0, 0});
  ASSERT_TRUE(config);
  EXPECT_TRUE(config->enabled);
  EXPECT_EQ(config->profile, 1);
  EXPECT_EQ(config->domain, 24);
}

TEST(HesaiPtcTime, AnAnswerCutShortIsRefusedInOneSentenceAtEveryLength) {
  const std::vector<std::pair<Bytes, int>> answers{
      {ptp_status(1), 0}, {port_data_set(9, own, 1, 0), 1}, {time_status_np(1, true, gm), 2},
      {grandmaster_settings(37, 0), 3}, {lidar_status(false, 2, true, true), 4}, {Bytes{1, 0, 0, 0}, 5}};
  for (const auto& [whole, which] : answers) {
    for (std::size_t size = 0; size < whole.size(); ++size) {
      const std::span<const std::uint8_t> cut(whole.data(), size);
      std::string message;
      switch (which) {
        case 0: if (auto r = ptc::parse_ptp_status(cut); !r) message = r.error().message; else continue; break;
        case 1: if (auto r = ptc::parse_port_data_set(cut); !r) message = r.error().message; else continue; break;
        case 2: if (auto r = ptc::parse_time_status_np(cut); !r) message = r.error().message; else continue; break;
        case 3: if (auto r = ptc::parse_grandmaster_settings_np(cut); !r) message = r.error().message; else continue; break;
        case 4:
          // The status answer needs its clock byte (@48 in this layout), not its reserved tail.
          if (auto r = ptc::parse_lidar_status(cut, ptc::StatusLayout::xt); !r) message = r.error().message;
          else { EXPECT_GE(size, 49u); continue; }
          break;
        default: if (auto r = ptc::parse_ptp_config(cut); !r) message = r.error().message; else continue; break;
      }
      EXPECT_NE(message.find("shorter than"), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos);
    }
  }
}

TEST(HesaiPtcTime, ALockedPtpSensorReportsItsOffsetGrandmasterDomainAndUtcOffset) {
  ptc::ClockReplies r;
  r.config = ptc::PtpConfig{true, 0, 5, 0};
  r.status = got(ptc::parse_lidar_status(lidar_status(false, 2, false, false), std::nullopt));
  r.ptp = got(ptc::parse_ptp_status(ptp_status(-250)));
  r.port = got(ptc::parse_port_data_set(port_data_set(9, own, 1, 0)));
  r.time_status = got(ptc::parse_time_status_np(time_status_np(-260, true, gm)));
  r.grandmaster = got(ptc::parse_grandmaster_settings_np(grandmaster_settings(37, 0x0C)));
  const sim::ClockStatus c = ptc::clock_status(r);
  EXPECT_EQ(c.source, sim::ClockSource::ptp);
  EXPECT_EQ(c.state, sim::ClockState::locked);
  EXPECT_EQ(c.ptp_domain, 5);
  EXPECT_EQ(c.offset_from_master_ns, -250);  // PTP STATUS first
  EXPECT_FALSE(c.path_delay_ns.has_value()) << "end-to-end: the peer delay means nothing";
  EXPECT_EQ(c.grandmaster, "001747.fffe.700038");
  EXPECT_EQ(c.utc_offset_s, 37);
  EXPECT_TRUE(c.ptp_timescale);
  EXPECT_EQ(c.stamps, sim::StampClock::sensor);
  EXPECT_EQ(c.reported_ns, 0) << "the caller says when it was read";
}

TEST(HesaiPtcTime, ItsOwnClockAsGrandmasterIsNoSynchronisation) {
  ptc::ClockReplies r;
  r.config = ptc::PtpConfig{true, 1, 0, 1};
  r.status = got(ptc::parse_lidar_status(lidar_status(false, 2, false, false), std::nullopt));
  r.port = got(ptc::parse_port_data_set(port_data_set(9, own, 2, 640)));
  r.time_status = got(ptc::parse_time_status_np(time_status_np(0, true, own)));
  const sim::ClockStatus c = ptc::clock_status(r);
  EXPECT_EQ(c.source, sim::ClockSource::gptp);
  EXPECT_EQ(c.state, sim::ClockState::free_running);
  EXPECT_EQ(c.grandmaster, "");
  EXPECT_EQ(c.path_delay_ns, 640);
  EXPECT_FALSE(c.utc_offset_s.has_value());
}

TEST(HesaiPtcTime, WithoutTheStatusThePortStateSaysTheLockAndAbsurdValuesAreKeptAsReported) {
  ptc::ClockReplies r;  // an older firmware: no 0x26, no 0x09
  r.port = got(ptc::parse_port_data_set(port_data_set(9, own, 1, 0)));
  r.time_status = got(ptc::parse_time_status_np(time_status_np(std::numeric_limits<std::int64_t>::max(), true, gm)));
  sim::ClockStatus c = ptc::clock_status(r);
  EXPECT_EQ(c.source, sim::ClockSource::ptp);
  EXPECT_EQ(c.state, sim::ClockState::locked);
  EXPECT_EQ(c.offset_from_master_ns, std::numeric_limits<std::int64_t>::max());
  r.port = got(ptc::parse_port_data_set(port_data_set(4, own, 1, 0)));  // LISTENING: not a PTP clock yet
  c = ptc::clock_status(r);
  EXPECT_EQ(c.source, sim::ClockSource::unknown);
  r.status = got(ptc::parse_lidar_status(lidar_status(false, 7, false, false), std::nullopt));  // no such value
  c = ptc::clock_status(r);
  EXPECT_EQ(c.source, sim::ClockSource::ptp);
  EXPECT_EQ(c.state, sim::ClockState::unknown);
}

TEST(HesaiPtcTime, WithPtpOffTheGpsInputsSayTheStateAndAQt128RunsFree) {
  ptc::ClockReplies r;
  r.config = ptc::PtpConfig{false, 0, 0, 0};
  r.status = got(ptc::parse_lidar_status(lidar_status(false, 0, true, true), std::nullopt));
  EXPECT_EQ(ptc::clock_status(r).source, sim::ClockSource::pps_nmea);
  EXPECT_EQ(ptc::clock_status(r).state, sim::ClockState::locked);
  r.status = got(ptc::parse_lidar_status(lidar_status(false, 0, false, false), std::nullopt));
  EXPECT_EQ(ptc::clock_status(r).state, sim::ClockState::free_running);
  r.status = got(ptc::parse_lidar_status(lidar_status(true, 0, false, false), std::nullopt));
  EXPECT_EQ(ptc::clock_status(r).source, sim::ClockSource::free_running);
  EXPECT_EQ(ptc::clock_status(ptc::ClockReplies{}).source, sim::ClockSource::unknown);
}
