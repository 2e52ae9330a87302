// SPDX-License-Identifier: Apache-2.0
// Angle-correction and firing-time CSV parsing: the real files, their textual variants (BOM,
// CRLF, header spellings, no final newline) and the ways a file can be wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "hesai_test_data.hpp"
#include "sim/hesai/hesai.hpp"

using namespace sim::hesai;
using hesai_test::data_path;
using hesai_test::read_text;

namespace {

std::string to_crlf_with_bom(const std::string& text) {
  std::string out = "\xEF\xBB\xBF";
  for (char c : text) {
    if (c == '\n') out += '\r';
    out += c;
  }
  return out;
}

std::string error_of(std::string_view text, std::optional<Model> model) {
  auto cal = Calibration::parse(text, model, "test.csv");
  EXPECT_FALSE(cal) << "accepted: " << text;
  return cal ? std::string() : cal.error().message;
}

}  // namespace

TEST(HesaiCalibration, Pandar64FileHasTheValuesOfTheReferenceNotes) {
  auto cal = Calibration::load(data_path("pandar64.calibration.csv"), Model::pandar64);
  ASSERT_TRUE(cal) << cal.error().message;
  ASSERT_EQ(cal->channels(), 64u);
  // Reference §1.2: "1,14.9,-1.042", "7,1.878,1.042", "64,-24.879,-1.042".
  EXPECT_FLOAT_EQ((*cal)[0].elevation_deg, 14.9f);
  EXPECT_FLOAT_EQ((*cal)[0].azimuth_offset_deg, -1.042f);
  EXPECT_FLOAT_EQ((*cal)[6].elevation_deg, 1.878f);
  EXPECT_FLOAT_EQ((*cal)[6].azimuth_offset_deg, 1.042f);
  EXPECT_FLOAT_EQ((*cal)[63].elevation_deg, -24.879f);
  EXPECT_FLOAT_EQ((*cal)[63].azimuth_offset_deg, -1.042f);
}

TEST(HesaiCalibration, Pandar40PExampleWithCrlfChannelHeaderAndNoFinalNewline) {
  const std::string text = read_text(data_path("pandar40p.example-calibration.csv"));
  ASSERT_NE(text.find("\r\n"), std::string::npos);
  ASSERT_NE(text.back(), '\n');
  auto cal = Calibration::parse(text, Model::pandar40p);
  ASSERT_TRUE(cal) << cal.error().message;
  ASSERT_EQ(cal->channels(), 40u);
  EXPECT_FLOAT_EQ((*cal)[0].elevation_deg, 15.21f);
  EXPECT_FLOAT_EQ((*cal)[39].elevation_deg, -24.569f);
  EXPECT_FLOAT_EQ((*cal)[39].azimuth_offset_deg, -1.042f);
}

TEST(HesaiCalibration, BomAndCrlfVariantsParseToTheSameAngles) {
  const std::string lf = read_text(data_path("pandarxt32.calibration.csv"));
  auto plain = Calibration::parse(lf, Model::pandar_xt32);
  auto bom = Calibration::parse(to_crlf_with_bom(lf), Model::pandar_xt32);
  auto laser_id = Calibration::parse("Laser id,Elevation,Azimuth" + lf.substr(lf.find('\n')),
                                     Model::pandar_xt32);
  auto no_header = Calibration::parse(lf.substr(lf.find('\n') + 1) + "\n\n\n", Model::pandar_xt32);
  ASSERT_TRUE(plain) << plain.error().message;
  ASSERT_TRUE(bom) << bom.error().message;
  ASSERT_TRUE(laser_id) << laser_id.error().message;
  ASSERT_TRUE(no_header) << no_header.error().message;
  for (std::size_t ch = 0; ch < 32; ++ch) {
    EXPECT_EQ((*plain)[ch].elevation_deg, (*bom)[ch].elevation_deg);
    EXPECT_EQ((*plain)[ch].azimuth_offset_deg, (*bom)[ch].azimuth_offset_deg);
    EXPECT_EQ((*plain)[ch].elevation_deg, (*laser_id)[ch].elevation_deg);
    EXPECT_EQ((*plain)[ch].elevation_deg, (*no_header)[ch].elevation_deg);
  }
  EXPECT_FLOAT_EQ((*plain)[0].elevation_deg, 14.972363f);
  EXPECT_FLOAT_EQ((*plain)[0].azimuth_offset_deg, 0.082385f);
}

TEST(HesaiCalibration, WrongChannelCountForTheModelIsRefusedWithBothCounts) {
  const std::string text = read_text(data_path("pandar64.calibration.csv"));
  const std::string message = error_of(text, Model::pandar40p);
  EXPECT_NE(message.find("64 channels"), std::string::npos) << message;
  EXPECT_NE(message.find("Pandar40P has 40"), std::string::npos) << message;

  // Without a model the file parses, and the assembler refuses the mismatch instead.
  auto cal = Calibration::parse(text, std::nullopt);
  ASSERT_TRUE(cal);
  AssemblerOptions options;
  options.model = Model::pandar_xt32;
  auto assembler = FrameAssembler::create(*cal, options);
  ASSERT_FALSE(assembler);
  EXPECT_NE(assembler.error().message.find("PandarXT32 has 32"), std::string::npos)
      << assembler.error().message;
}

TEST(HesaiCalibration, MalformedRowsAreReportedWithTheirLineNumber) {
  std::string text = read_text(data_path("pandar64.calibration.csv"));
  // Line 7 of the file is channel 6.
  const std::size_t start = [&] {
    std::size_t pos = 0;
    for (int line = 1; line < 7; ++line) pos = text.find('\n', pos) + 1;
    return pos;
  }();
  text.replace(start, text.find('\n', start) - start, "6,abc,1.042");
  const std::string message = error_of(text, Model::pandar64);
  EXPECT_NE(message.find("test.csv:7:"), std::string::npos) << message;
  EXPECT_NE(message.find("6,abc,1.042"), std::string::npos) << message;
}

TEST(HesaiCalibration, GarbageEmptyAndImpossibleFilesGiveOneSentence) {
  EXPECT_NE(error_of("", Model::pandar64).find("no calibration lines"), std::string::npos);
  EXPECT_NE(error_of("\xEF\xBB\xBF\r\n\r\n", std::nullopt).find("no calibration lines"),
            std::string::npos);
  EXPECT_NE(error_of("Channel,Elevation,Azimuth\n", Model::pandar64).find("no calibration"),
            std::string::npos);
  EXPECT_NE(error_of("hello\nworld\n", std::nullopt).find("test.csv:2:"), std::string::npos);
  EXPECT_NE(error_of(std::string("Channel\n1,2\0,3\n", 15), std::nullopt).find("NUL"),
            std::string::npos);
  EXPECT_NE(error_of("1,1,1\n1,2,2\n", std::nullopt).find("appears twice"), std::string::npos);
  EXPECT_NE(error_of("1,1,1\n3,2,2\n", std::nullopt).find("no line for channel 2"),
            std::string::npos);
  EXPECT_NE(error_of("0,1,1\n", std::nullopt).find("out of range"), std::string::npos);
  EXPECT_NE(error_of("1,95,1\n", std::nullopt).find("±90°"), std::string::npos);
  EXPECT_NE(error_of("1,nan,1\n", std::nullopt).find("test.csv:1:"), std::string::npos);
  EXPECT_NE(error_of("1,2,3,4\n", std::nullopt).find("three numbers"), std::string::npos);
  EXPECT_NE(error_of("1,2\n", std::nullopt).find("three numbers"), std::string::npos);
  // Trailing empty fields, as spreadsheets write them, are fine.
  EXPECT_TRUE(Calibration::parse("Channel,Elevation,Azimuth,,\n1, 2.5 ,-1,\n", std::nullopt));

  auto missing = Calibration::load(data_path("no-such-file.csv"), Model::pandar64);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("cannot open"), std::string::npos);
}

TEST(HesaiFiretimes, Pandar64ExampleFileMatchesTheBuiltInTable) {
  auto fire = FiretimeCorrection::load(data_path("pandar64.example-firetimes.csv"),
                                       Model::pandar64);
  ASSERT_TRUE(fire) << fire.error().message;
  ASSERT_EQ(fire->channels(), 64u);
  // Rows are sorted by time in the file, not by channel (reference §1.2).
  EXPECT_DOUBLE_EQ((*fire)[50], -3.62);   // channel 51
  EXPECT_DOUBLE_EQ((*fire)[0], -23.18);   // channel 1
  for (unsigned ch = 0; ch < 64; ++ch) {
    EXPECT_EQ(std::lround((*fire)[ch] * 1000.0), Packet::channel_offset_ns(Model::pandar64, ch))
        << "channel " << ch + 1;
  }
  auto wrong = FiretimeCorrection::parse(read_text(data_path("pandar64.example-firetimes.csv")),
                                         Model::pandar_xt32, "fire.csv");
  ASSERT_FALSE(wrong);
  EXPECT_NE(wrong.error().message.find("64 channels"), std::string::npos);
  auto garbage = FiretimeCorrection::parse("Channel,fire time(us)\n1,-3.6\n2,fast\n",
                                           std::nullopt, "fire.csv");
  ASSERT_FALSE(garbage);
  EXPECT_NE(garbage.error().message.find("fire.csv:3:"), std::string::npos);
}
