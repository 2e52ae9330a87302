// SPDX-License-Identifier: Apache-2.0
// The status line: redrawn in place on a terminal, silent in a log until its one summary line.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "sim/apps/status_line.hpp"

namespace {

std::string contents(std::FILE* file) {
  std::fflush(file);
  std::rewind(file);
  std::string text;
  char buffer[256];
  while (const std::size_t n = std::fread(buffer, 1, sizeof buffer, file)) text.append(buffer, n);
  return text;
}

TEST(StatusLine, InALogOnlyTheSummaryLineAppears) {
  std::FILE* log = std::tmpfile();
  ASSERT_NE(log, nullptr);
  sim::apps::StatusLine status("sim_test", /*live=*/false, /*quiet=*/false, log);
  status.update("frames 1");
  status.update("frames 2");
  status.finish(sim::apps::fields({{"frames", "2"}, {"rate", sim::apps::number(10.0) + " Hz"}}));
  EXPECT_EQ(contents(log), "sim_test: frames 2  rate 10.0 Hz\n");
  std::fclose(log);
}

TEST(StatusLine, OnATerminalTheLineIsRedrawnInPlaceAndClearedBeforeTheSummary) {
  std::FILE* terminal = std::tmpfile();
  ASSERT_NE(terminal, nullptr);
  sim::apps::StatusLine status("sim_test", /*live=*/true, /*quiet=*/false, terminal);
  status.update("frames 1");
  status.note("camera unplugged");
  status.finish("frames 1");
  EXPECT_EQ(contents(terminal),
            "\r\033[Kframes 1\r\033[Ksim_test: camera unplugged\n\r\033[K"
            "sim_test: frames 1\n");
  std::fclose(terminal);
}

TEST(StatusLine, QuietPrintsNothingButNotes) {
  std::FILE* log = std::tmpfile();
  ASSERT_NE(log, nullptr);
  sim::apps::StatusLine status("sim_test", /*live=*/true, /*quiet=*/true, log);
  status.update("frames 1");
  status.finish("frames 1");
  EXPECT_EQ(contents(log), "");
  std::fclose(log);
}

TEST(StatusLine, BandwidthIsShownInTheUnitThatSuitsIt) {
  EXPECT_EQ(sim::apps::bandwidth(22'412'000), "22.4 MB/s");
  EXPECT_EQ(sim::apps::bandwidth(3'140), "3.1 kB/s");
  EXPECT_EQ(sim::apps::bandwidth(12), "12 B/s");
  EXPECT_EQ(sim::apps::bandwidth(0), "0 B/s");
}

}  // namespace
