// JSON output through nlohmann-json: hostile strings stay valid JSON, numbers keep the digits the
// reports have always printed.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "primlabel/geometry/json_text.hpp"

namespace primlabel {
namespace {

TEST(JsonText, HostileStringsGiveValidJsonThatReadsBack) {
  const std::string quotes = "a \"quoted\" \\ back\\slash";
  const std::string controls = std::string("tab\tnew\nline\r\x01\x1f end") + '\0' + "after nul";
  const json::Json line = {{"quotes", quotes}, {"controls", controls}};
  const std::string text = json::dump(line);
  EXPECT_EQ(text.find('\n'), std::string::npos) << text;  // one line: control chars escaped
  const json::Json back = json::Json::parse(text);
  EXPECT_EQ(back["quotes"], quotes);
  EXPECT_EQ(back["controls"], controls);
}

TEST(JsonText, InvalidUtf8IsReplacedInsteadOfThrowing) {
  const std::string bad = "scan_\xff\xfe_\xc3(.pcd";  // stray bytes and a truncated sequence
  const json::Json line = {{"file", bad}, {"ok", "caf\xc3\xa9"}};
  std::string text;
  ASSERT_NO_THROW(text = json::dump(line));
  const json::Json back = json::Json::parse(text);  // valid UTF-8 now
  const std::string file = back["file"];
  EXPECT_NE(file.find("\xef\xbf\xbd"), std::string::npos) << text;  // U+FFFD
  EXPECT_EQ(file.substr(0, 5), "scan_");
  EXPECT_EQ(back["ok"], "caf\xc3\xa9");  // valid UTF-8 is kept as it is
}

TEST(JsonText, NumbersKeepThePrintfDigitsAndNonFiniteIsNull) {
  EXPECT_EQ(json::dump(json::rounded(1.0 / 3.0, "%.6f")), "0.333333");
  EXPECT_EQ(json::dump(json::rounded(0.5, "%.6f")), "0.5");
  EXPECT_EQ(json::dump(json::rounded(12345.678, "%.1f")), "12345.7");
  EXPECT_EQ(json::dump(json::rounded(0.000123456789, "%.6g")), "0.000123457");
  EXPECT_EQ(json::dump(json::rounded(std::nan(""), "%.6f")), "null");
  EXPECT_EQ(json::dump(json::rounded(std::numeric_limits<double>::infinity(), "%.3f")), "null");
  EXPECT_EQ(json::dump(json::whole(41.6)), "42");
  EXPECT_EQ(json::dump(json::whole(std::nan(""))), "null");
  EXPECT_EQ(json::dump(json::number_or_null(-std::numeric_limits<double>::infinity())), "null");
}

TEST(JsonText, KeysKeepTheirOrder) {
  const json::Json line = {{"z", 1}, {"a", 2}, {"m", 3}};
  EXPECT_EQ(json::dump(line), R"({"z":1,"a":2,"m":3})");
}

}  // namespace
}  // namespace primlabel
