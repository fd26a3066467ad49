#include "report.hpp"

#include <string>

#include "primlabel/geometry/json_text.hpp"

namespace primlabel::client::loadgen {

namespace {

struct Figures {
  std::string mode, transport;
  double clouds_per_s, points_per_s;
  double p50, p90, p95, p99, max;  // ms
};

Figures figures_of(const StepResult& r) {
  const LoadStats& s = r.stats;
  const double elapsed = r.elapsed_s > 0 ? r.elapsed_s : 1;
  return {r.spec.mode == LoadMode::kClosed ? "closed" : "open",
          r.spec.unary ? "unary" : "stream",
          s.ok() / elapsed,
          s.points() / elapsed,
          1e3 * s.percentile(50),
          1e3 * s.percentile(90),
          1e3 * s.percentile(95),
          1e3 * s.percentile(99),
          1e3 * s.max()};
}

std::string errors_text(const LoadStats& s, const char* sep, const char* eq) {
  std::string text;
  for (const auto& [status, n] : s.errors_by_status())
    text += (text.empty() ? "" : sep) + status + eq + std::to_string(n);
  return text;
}

std::string counts_text(const ServerCounts& c) {
  std::string text;
  for (const auto& [status, n] : c.by_status)
    text += (text.empty() ? "" : ", ") + status + " " + std::to_string(static_cast<long long>(n));
  return text;
}

void write_text(std::FILE* out, const std::vector<ReportRow>& rows) {
  std::fprintf(out, "%-6s %-6s %5s %7s %8s %7s %6s %9s %11s %8s %8s %8s %8s %8s\n", "mode", "calls",
               "conc", "rate", "elapsed", "ok", "errors", "clouds/s", "points/s", "p50 ms",
               "p90 ms", "p95 ms", "p99 ms", "max ms");
  for (const auto& row : rows) {
    const StepResult& r = row.step;
    const Figures f = figures_of(r);
    std::fprintf(
        out, "%-6s %-6s %5d %7.1f %7.1fs %7llu %6llu %9.2f %11.0f %8.1f %8.1f %8.1f %8.1f %8.1f\n",
        f.mode.c_str(), f.transport.c_str(), r.spec.concurrency,
        r.spec.mode == LoadMode::kOpen ? r.spec.rate : 0.0, r.elapsed_s,
        static_cast<unsigned long long>(r.stats.ok()),
        static_cast<unsigned long long>(r.stats.errors()), f.clouds_per_s, f.points_per_s, f.p50,
        f.p90, f.p95, f.p99, f.max);
  }
  for (const auto& row : rows) {
    const StepResult& r = row.step;
    if (r.stats.errors() > 0)
      std::fprintf(out, "conc %d: errors %s\n", r.spec.concurrency,
                   errors_text(r.stats, ", ", " ").c_str());
    if (r.stats.rejected() > 0)
      std::fprintf(out,
                   "conc %d: %llu calls rejected at admission (%s: the server's workers and "
                   "queue were full)%s\n",
                   r.spec.concurrency, static_cast<unsigned long long>(r.stats.rejected()),
                   kRejectedStatus,
                   r.spec.mode == LoadMode::kClosed ? "; callers backed off before resending" : "");
    if (r.stats.skipped() > 0)
      std::fprintf(out, "conc %d: %llu calls not sent (client had --max-outstanding in flight)\n",
                   r.spec.concurrency, static_cast<unsigned long long>(r.stats.skipped()));
    if (row.server) {
      const auto sent = r.stats.ok() + r.stats.errors();
      std::fprintf(out, "conc %d: server counted %lld requests (%s); loadgen sent %llu: %s\n",
                   r.spec.concurrency, static_cast<long long>(row.server->total),
                   counts_text(*row.server).c_str(), static_cast<unsigned long long>(sent),
                   row.server->total == static_cast<double>(sent) ? "match" : "MISMATCH");
    }
  }
}

void write_csv(std::FILE* out, const std::vector<ReportRow>& rows) {
  std::fprintf(out,
               "mode,calls,concurrency,rate,elapsed_s,ok,errors,skipped,clouds_per_s,points_per_s,"
               "p50_ms,p90_ms,p95_ms,p99_ms,max_ms,errors_by_status,server_requests,"
               "server_by_status,rejected\n");
  for (const auto& row : rows) {
    const StepResult& r = row.step;
    const Figures f = figures_of(r);
    std::string server_total, server_by;
    if (row.server) {
      server_total = std::to_string(static_cast<long long>(row.server->total));
      for (const auto& [status, n] : row.server->by_status)
        server_by += (server_by.empty() ? "" : ";") + status + "=" +
                     std::to_string(static_cast<long long>(n));
    }
    std::fprintf(
        out, "%s,%s,%d,%g,%.3f,%llu,%llu,%llu,%.3f,%.0f,%.2f,%.2f,%.2f,%.2f,%.2f,%s,%s,%s,%llu\n",
        f.mode.c_str(), f.transport.c_str(), r.spec.concurrency,
        r.spec.mode == LoadMode::kOpen ? r.spec.rate : 0.0, r.elapsed_s,
        static_cast<unsigned long long>(r.stats.ok()),
        static_cast<unsigned long long>(r.stats.errors()),
        static_cast<unsigned long long>(r.stats.skipped()), f.clouds_per_s, f.points_per_s, f.p50,
        f.p90, f.p95, f.p99, f.max, errors_text(r.stats, ";", "=").c_str(), server_total.c_str(),
        server_by.c_str(), static_cast<unsigned long long>(r.stats.rejected()));
  }
}

// Status names come from the server's metrics page as well as from gRPC: nlohmann escapes them.
void write_json(std::FILE* out, const std::vector<ReportRow>& rows) {
  json::Json steps = json::Json::array();
  for (const ReportRow& row : rows) {
    const StepResult& r = row.step;
    const Figures f = figures_of(r);
    json::Json errors = json::Json::object();
    for (const auto& [status, n] : r.stats.errors_by_status()) errors[status] = n;
    json::Json step = {
        {"mode", f.mode},
        {"calls", f.transport},
        {"concurrency", r.spec.concurrency},
        {"rate", json::rounded(r.spec.mode == LoadMode::kOpen ? r.spec.rate : 0.0, "%g")},
        {"elapsed_s", json::rounded(r.elapsed_s, "%.3f")},
        {"ok", r.stats.ok()},
        {"errors", r.stats.errors()},
        {"rejected", r.stats.rejected()},
        {"skipped", r.stats.skipped()},
        {"clouds_per_s", json::rounded(f.clouds_per_s, "%.3f")},
        {"points_per_s", json::whole(f.points_per_s)},
        {"latency_ms",
         {{"p50", json::rounded(f.p50, "%.2f")},
          {"p90", json::rounded(f.p90, "%.2f")},
          {"p95", json::rounded(f.p95, "%.2f")},
          {"p99", json::rounded(f.p99, "%.2f")},
          {"max", json::rounded(f.max, "%.2f")}}},
        {"errors_by_status", std::move(errors)}};
    if (row.server) {
      json::Json by_status = json::Json::object();
      for (const auto& [status, n] : row.server->by_status) by_status[status] = json::whole(n);
      step["server"] = {{"requests", json::whole(row.server->total)},
                        {"by_status", std::move(by_status)}};
    }
    steps.push_back(std::move(step));
  }
  std::fprintf(out, "%s\n", json::dump({{"steps", std::move(steps)}}).c_str());
}

}  // namespace

void write_report(std::FILE* out, const std::vector<ReportRow>& rows, ReportFormat format) {
  switch (format) {
    case ReportFormat::kText:
      return write_text(out, rows);
    case ReportFormat::kCsv:
      return write_csv(out, rows);
    case ReportFormat::kJson:
      return write_json(out, rows);
  }
}

}  // namespace primlabel::client::loadgen
