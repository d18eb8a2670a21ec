// The server's log lines: one JSON object per line that parses back with its fields, outside text
// escaped (quotes, newlines) so one event can never forge another; levels filter.
#include <gtest/gtest.h>

#include "core/log.h"

using namespace peakcast;

TEST(Log, JsonLinesParseBackWithTheirFields) {
  const std::string evil = "a \"quoted\"\nforged {\"level\":\"error\"} line\\";
  const std::string line =
      log::format_line(log::Level::Warn, evil, {{"path", "/data/x\ny.nrrd"}, {"n", 3}}, log::Format::Json, "T");
  EXPECT_EQ(line.find('\n'), std::string::npos) << line;
  const auto j = nlohmann::json::parse(line);
  EXPECT_EQ(j["msg"], evil);
  EXPECT_EQ(j["level"], "warn");
  EXPECT_EQ(j["ts"], "T");
  EXPECT_EQ(j["path"], "/data/x\ny.nrrd");
  EXPECT_EQ(j["n"], 3);
}

TEST(Log, TextLinesStayOneLine) {
  const std::string line =
      log::format_line(log::Level::Info, "loaded\nfake line", {{"path", "a\r\nb"}}, log::Format::Text, "T");
  EXPECT_EQ(line, "T info loaded fake line path=a  b");
}

TEST(Log, FieldsCannotOverrideTheEnvelope) {
  const auto j = nlohmann::json::parse(
      log::format_line(log::Level::Info, "m", {{"level", "error"}, {"msg", "x"}}, log::Format::Json, "T"));
  EXPECT_EQ(j["level"], "info");
  EXPECT_EQ(j["msg"], "m");
}

TEST(Log, LevelsAndFormatsParseOrAreRefused) {
  EXPECT_EQ(log::parse_level("debug"), log::Level::Debug);
  EXPECT_EQ(log::parse_level("warn"), log::Level::Warn);
  EXPECT_EQ(log::parse_format("json"), log::Format::Json);
  EXPECT_THROW(log::parse_level("verbose"), std::invalid_argument);
  EXPECT_THROW(log::parse_format("xml"), std::invalid_argument);
  log::configure(log::Level::Error, log::Format::Text);
  EXPECT_EQ(log::level(), log::Level::Error);
  testing::internal::CaptureStderr();
  log::info("hidden");
  log::error("shown");
  const std::string out = testing::internal::GetCapturedStderr();
  EXPECT_EQ(out.find("hidden"), std::string::npos);
  EXPECT_NE(out.find("error shown"), std::string::npos) << out;
  log::configure(log::Level::Info, log::Format::Text);
}
