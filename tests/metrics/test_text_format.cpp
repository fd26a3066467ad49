// Serialisation to the Prometheus text exposition format 0.0.4.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "primlabel/metrics/metrics.hpp"

namespace primlabel::metrics {
namespace {

TEST(TextFormat, SmallRegistryExactly) {
  Registry registry;
  auto& requests = BuildCounter()
                       .Name("primlabel_requests_total")
                       .Help("Requests served.")
                       .Labels({{"service", "primlabel"}})
                       .Register(registry);
  requests.Add({{"method", "Label"}, {"status", "OK"}}).Increment(3);
  requests.Add({{"method", "Label"}, {"status", "INTERNAL"}}).Increment();
  BuildGauge()
      .Name("primlabel_inflight_requests")
      .Help("In flight.")
      .Register(registry)
      .Add({})
      .Set(2.5);
  auto& latency =
      BuildHistogram().Name("primlabel_request_seconds").Help("Latency.").Register(registry);
  auto& label_latency = latency.Add({{"method", "Label"}}, {0.5, 1});
  for (double v : {0.25, 0.5, 0.75, 4.0}) label_latency.Observe(v);
  BuildCounter().Name("primlabel_unused_total").Help("No series yet.").Register(registry);

  EXPECT_EQ(
      registry.Serialize(),
      "# HELP primlabel_requests_total Requests served.\n"
      "# TYPE primlabel_requests_total counter\n"
      "primlabel_requests_total{method=\"Label\",service=\"primlabel\",status=\"INTERNAL\"} 1\n"
      "primlabel_requests_total{method=\"Label\",service=\"primlabel\",status=\"OK\"} 3\n"
      "# HELP primlabel_inflight_requests In flight.\n"
      "# TYPE primlabel_inflight_requests gauge\n"
      "primlabel_inflight_requests 2.5\n"
      "# HELP primlabel_request_seconds Latency.\n"
      "# TYPE primlabel_request_seconds histogram\n"
      "primlabel_request_seconds_bucket{method=\"Label\",le=\"0.5\"} 2\n"
      "primlabel_request_seconds_bucket{method=\"Label\",le=\"1\"} 3\n"
      "primlabel_request_seconds_bucket{method=\"Label\",le=\"+Inf\"} 4\n"
      "primlabel_request_seconds_sum{method=\"Label\"} 5.5\n"
      "primlabel_request_seconds_count{method=\"Label\"} 4\n");
}

TEST(TextFormat, EscapesLabelValuesAndHelp) {
  Registry registry;
  BuildGauge()
      .Name("escaped")
      .Help("back\\slash and\nnewline, \"quotes\" kept")
      .Register(registry)
      .Add({{"path", "C:\\dir \"x\"\nnext"}})
      .Set(1);
  EXPECT_EQ(registry.Serialize(),
            "# HELP escaped back\\\\slash and\\nnewline, \"quotes\" kept\n"
            "# TYPE escaped gauge\n"
            "escaped{path=\"C:\\\\dir \\\"x\\\"\\nnext\"} 1\n");
}

TEST(TextFormat, HistogramWithoutLabelsAndEmptyHelp) {
  Registry registry;
  auto& histogram = BuildHistogram().Name("h").Register(registry).Add({}, {1});
  histogram.Observe(2);
  EXPECT_EQ(registry.Serialize(),
            "# TYPE h histogram\n"
            "h_bucket{le=\"1\"} 0\n"
            "h_bucket{le=\"+Inf\"} 1\n"
            "h_sum 2\n"
            "h_count 1\n");
}

TEST(TextFormat, ValuesRoundTripAndSpecialValuesAreSpelledAsPrometheusDoes) {
  EXPECT_EQ(format_value(0), "0");
  EXPECT_EQ(format_value(-3), "-3");
  EXPECT_EQ(format_value(0.1), "0.1");
  EXPECT_EQ(format_value(1e21), "1e+21");
  EXPECT_EQ(format_value(INFINITY), "+Inf");
  EXPECT_EQ(format_value(-INFINITY), "-Inf");
  EXPECT_EQ(format_value(NAN), "NaN");
  for (double v : {1.0 / 3.0, 123456789.123456789, 5e-324, 1.7976931348623157e308})
    EXPECT_EQ(std::strtod(format_value(v).c_str(), nullptr), v);
}

}  // namespace
}  // namespace primlabel::metrics
