// SPDX-License-Identifier: Apache-2.0
// The --config file's reader on its own (no CLI11): what each YAML shape becomes, and one
// sentence for a file that is not a map of options.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "sim/apps/yaml_config.hpp"

namespace {

using sim::apps::ConfigEntry;
using sim::apps::YamlConfig;

sim::Expected<std::vector<ConfigEntry>> read(const YamlConfig& config, const std::string& text) {
  std::istringstream input(text);
  return config.read(input);
}

TEST(YamlConfig, KeysBecomeDashedOptionNamesWithTheirValuesInFileOrder) {
  auto entries = read(YamlConfig(), "rt_priority: 20\nroi: [0, 0, 640, 480]\ncontrols: {gain: 3, exposure: 10}\n");
  ASSERT_TRUE(entries) << entries.error().message;
  ASSERT_EQ(entries->size(), 3U);
  EXPECT_EQ((*entries)[0].name, "rt-priority");
  EXPECT_EQ((*entries)[0].inputs, std::vector<std::string>{"20"});
  EXPECT_EQ((*entries)[1].inputs, (std::vector<std::string>{"0", "0", "640", "480"}));
  EXPECT_EQ((*entries)[2].inputs, (std::vector<std::string>{"gain=3", "exposure=10"}));
}

TEST(YamlConfig, AKeyWithoutAValueLeavesItsOptionAlone) {
  auto entries = read(YamlConfig(), "stream:\nquiet: true\n");
  ASSERT_TRUE(entries) << entries.error().message;
  ASSERT_EQ(entries->size(), 1U);
  EXPECT_EQ((*entries)[0].name, "quiet");
}

TEST(YamlConfig, AnEmptyFileHasNoOptions) {
  auto entries = read(YamlConfig(), "");
  ASSERT_TRUE(entries) << entries.error().message;
  EXPECT_TRUE(entries->empty());
}

TEST(YamlConfig, AFileThatIsNotAMapIsRefusedInOneSentence) {
  auto entries = read(YamlConfig(), "- a\n- b\n");
  ASSERT_FALSE(entries);
  EXPECT_EQ(entries.error().code, sim::ErrorCode::invalid_argument);
  EXPECT_EQ(entries.error().message, "the config file must be a map of option: value");
}

TEST(YamlConfig, AValueNestedTooDeepIsRefusedWithItsKeyAndLine) {
  auto entries = read(YamlConfig(), "stream: /a\nroi:\n  - [1, 2]\n");
  ASSERT_FALSE(entries);
  EXPECT_NE(entries.error().message.find("'roi' (line 3) nests too deep"), std::string::npos)
      << entries.error().message;
}

TEST(YamlConfig, BrokenYamlIsRefusedWithItsLine) {
  auto entries = read(YamlConfig(), "a: 1\nstream: [unclosed\n");
  ASSERT_FALSE(entries);
  EXPECT_NE(entries.error().message.find("not valid YAML"), std::string::npos) << entries.error().message;
  EXPECT_NE(entries.error().message.find("at line"), std::string::npos) << entries.error().message;
}

TEST(YamlConfig, RelativeFileNamesOfPathOptionsStartAtTheFilesFolder) {
  YamlConfig config({"camera_info"});
  config.add_path_option("calibration");
  config.set_file("/etc/sim/hesai/top.yaml");
  auto entries = read(config,
                            "calibration: unit.csv\ncamera-info: file:///etc/c.yaml\n"
                            "firetimes: /abs/f.csv\nlabel: notes.txt\n");
  ASSERT_TRUE(entries) << entries.error().message;
  ASSERT_EQ(entries->size(), 4U);
  EXPECT_EQ((*entries)[0].inputs[0], "/etc/sim/hesai/unit.csv");
  EXPECT_EQ((*entries)[1].inputs[0], "file:///etc/c.yaml");  // a URL stays as written
  EXPECT_EQ((*entries)[2].inputs[0], "/abs/f.csv");          // not a path option
  EXPECT_EQ((*entries)[3].inputs[0], "notes.txt");
}

}  // namespace
