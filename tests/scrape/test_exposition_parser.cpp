// Parsing the text exposition format: what prometheus-cpp's serializer writes, and errors on
// malformed input.

#include <gtest/gtest.h>
#include <prometheus/counter.h>
#include <prometheus/gauge.h>
#include <prometheus/histogram.h>
#include <prometheus/registry.h>
#include <prometheus/text_serializer.h>

#include <cmath>
#include <stdexcept>

#include "primlabel/scrape/exposition_parser.hpp"

namespace primlabel::scrape {
namespace {

TEST(ExpositionParser, ReadsWhatPrometheusCppWrites) {
  prometheus::Registry registry;
  auto& requests = prometheus::BuildCounter().Name("req_total").Help("h").Register(registry);
  requests.Add({{"model", "tabletop"}, {"odd", "a\\b\"c\nd"}}).Increment(41);
  prometheus::BuildGauge().Name("depth").Register(registry).Add({}).Set(-0.125);
  auto& histogram = prometheus::BuildHistogram().Name("lat").Register(registry).Add(
      {{"stage", "crf"}}, prometheus::Histogram::BucketBoundaries{0.1});
  histogram.Observe(0.05);
  histogram.Observe(3);

  const auto samples = parse_exposition(prometheus::TextSerializer().Serialize(registry.Collect()));
  ASSERT_EQ(samples.size(), 6u);
  EXPECT_EQ(samples[0].name, "req_total");
  EXPECT_EQ(samples[0].labels, (Labels{{"model", "tabletop"}, {"odd", "a\\b\"c\nd"}}));
  EXPECT_EQ(samples[0].value, 41);
  EXPECT_EQ(samples[1].name, "depth");
  EXPECT_TRUE(samples[1].labels.empty());
  EXPECT_EQ(samples[1].value, -0.125);
  // prometheus-cpp writes a histogram's count and sum before its buckets.
  EXPECT_EQ(samples[2].name, "lat_count");
  EXPECT_EQ(samples[2].value, 2);
  EXPECT_EQ(samples[3].name, "lat_sum");
  EXPECT_EQ(samples[3].value, 3.05);
  EXPECT_EQ(samples[4].name, "lat_bucket");
  EXPECT_EQ(samples[4].labels, (Labels{{"le", "0.1"}, {"stage", "crf"}}));
  EXPECT_EQ(samples[4].value, 1);
  EXPECT_EQ(samples[5].labels.at("le"), "+Inf");
  EXPECT_EQ(samples[5].value, 2);
  EXPECT_EQ(sum_samples(samples, "req_total", {{"model", "tabletop"}}), 41);
  EXPECT_EQ(sum_samples(samples, "req_total", {{"model", "other"}}), 0);
}

TEST(ExpositionParser, AcceptsWhatPrometheusWrites) {
  const auto samples = parse_exposition(
      "# a free comment\n"
      "\n"
      "# HELP up  whether the target is up\r\n"
      "# TYPE up gauge\n"
      "up 1 1700000000000\n"
      "x{a=\"1\",} +Inf\n"
      "x{ a = \"2\" } -Inf\n"
      "y NaN\n"
      "w Nan\n"     // prometheus-cpp's spelling (its exposer's empty summaries)
      "z 1.5e-3");  // no final newline
  ASSERT_EQ(samples.size(), 6u);
  EXPECT_EQ(samples[0].value, 1);
  EXPECT_EQ(samples[1].value, INFINITY);
  EXPECT_EQ(samples[2].labels.at("a"), "2");
  EXPECT_EQ(samples[2].value, -INFINITY);
  EXPECT_TRUE(std::isnan(samples[3].value));
  EXPECT_TRUE(std::isnan(samples[4].value));
  EXPECT_EQ(samples[5].value, 1.5e-3);
}

void expect_error_on_line(const std::string& text, int line) {
  try {
    parse_exposition(text);
    ADD_FAILURE() << "no error for: " << text;
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("line " + std::to_string(line) + ":", 0), 0u)
        << e.what() << " for: " << text;
  }
}

TEST(ExpositionParser, RejectsMalformedInputNamingTheLine) {
  expect_error_on_line("ok 1\nbad\n", 2);            // no value
  expect_error_on_line("ok 1\n\nx{a=\"1\" 2\n", 3);  // unclosed labels
  expect_error_on_line("x{a=1} 2\n", 1);             // unquoted value
  expect_error_on_line("x{a=\"unterminated} 2\n", 1);
  expect_error_on_line("x{a=\"\\t\"} 2\n", 1);        // unknown escape
  expect_error_on_line("x{a=\"1\",a=\"2\"} 2\n", 1);  // duplicate label
  expect_error_on_line("x{__name__x=\"1\"}2\n", 1);   // no blank before the value
  expect_error_on_line("x{9a=\"1\"} 2\n", 1);         // bad label name
  expect_error_on_line("9x 1\n", 1);                  // bad metric name
  expect_error_on_line("x one\n", 1);                 // bad value
  expect_error_on_line("x 1 2 3\n", 1);               // trailing text
  expect_error_on_line("x 1 12.5\n", 1);              // fractional timestamp
  expect_error_on_line("x inf\n", 1);                 // not Prometheus' spelling
  expect_error_on_line("# TYPE x countr\n", 1);       // unknown type
  expect_error_on_line("# TYPE\n", 1);                // no name
}

}  // namespace
}  // namespace primlabel::scrape
