// health, models and info: small reads of the server's state, printed for people on stdout.

#include <chrono>
#include <cstdio>
#include <string>

#include "commands.hpp"
#include "common/human_format.hpp"
#include "status_exit_codes.hpp"

namespace primlabel::client::tools {

namespace {
std::int64_t now_unix_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

int run_health(Client& client, const std::string& service) {
  HealthStatus status;
  try {
    status = client.health(service);
  } catch (const ClientError& e) {
    if (e.code() != grpc::StatusCode::NOT_FOUND) throw;
    status = HealthStatus::kServiceUnknown;  // the health service's answer for unknown names
  }
  std::printf("%s\n", health_status_name(status).c_str());
  if (status == HealthStatus::kServing) return kExitOk;
  return status == HealthStatus::kServiceUnknown ? kExitRejected : kExitUnavailable;
}

int run_models(Client& client) {
  const auto models = client.list_models();
  std::printf("%-24s %-20s %7s %8s %s\n", "MODEL", "VERSION", "CLASSES", "VAL-ACC", "LOADED");
  const std::int64_t now = now_unix_ms();
  for (const auto& m : models) {
    std::string loaded;
    for (const auto& v : m.loaded_versions()) loaded += (loaded.empty() ? "" : ",") + v;
    if (m.loaded_unix_ms() != 0)
      loaded += " (loaded " + describe_age_ms(now - m.loaded_unix_ms()) + " ago)";
    std::printf("%-24s %-20s %7u %8s %s%s\n", m.name().c_str(), m.version().c_str(), m.classes(),
                score_or_na(m.validation_accuracy()).c_str(), loaded.c_str(),
                m.is_default() ? " (default)" : "");
  }
  if (models.empty()) std::fprintf(stderr, "primlabel: the server serves no models\n");
  return kExitOk;
}

int run_info(Client& client, const std::string& model, const std::string& version) {
  const v1::ModelMetadata m = client.model_metadata(model, version);
  std::printf("model      %s\nversion    %s\nkind       %s\n", m.name().c_str(),
              m.version().c_str(), v1::ModelKind_Name(m.kind()).c_str());
  std::printf("file       %s (crc32 %08x)\n", m.path().c_str(), m.model_crc32());
  std::printf("created    %s by %s\n", describe_unix_ms(m.created_unix_ms(), now_unix_ms()).c_str(),
              m.created_by().empty() ? "unknown" : m.created_by().c_str());
  const auto& f = m.features();
  std::printf(
      "features   %s, %u values; normal radius %g (k %u); feature radius %g (k %u); "
      "voxel %g; radii overridable: %s\n",
      v1::Descriptor_Name(f.descriptor_kind()).c_str(), f.descriptor_dim(), f.normal_radius(),
      f.normal_k(), f.feature_radius(), f.feature_k(), f.voxel_size(),
      f.radii_overridable() ? "yes" : "no");
  if (f.extra_feature_radii_size() > 0 || f.surface_variation_features()) {
    std::string scales;
    for (float r : f.extra_feature_radii()) {
      char radius[32];
      std::snprintf(radius, sizeof radius, "%s%g", scales.empty() ? "" : ", ", r);
      scales += radius;
    }
    std::printf("multiscale the descriptor also at radii %s; surface variations: %s\n",
                scales.empty() ? "none" : scales.c_str(),
                f.surface_variation_features() ? "yes" : "no");
  }
  if (f.shape_evidence())
    std::printf("shape      evidence: the class of each point on the box or cylinder fitted to "
                "its table-top object, one more value a class\n");
  std::printf("graph      k %u, radius %g\n", m.graph().k(), m.graph().radius());
  // No validation points: no accuracy and no F1 to show, not 0 or nan.
  const bool validated = m.validation().points() > 0;
  std::printf("validation %s accuracy on %llu points\n",
              validated ? score_or_na(m.validation().accuracy(), 4).c_str() : "n/a",
              static_cast<unsigned long long>(m.validation().points()));
  std::printf(
      "classes    (probability columns in this order; F1 n/a: undefined, no validation points of "
      "the class)\n");
  for (int i = 0; i < m.classes_size(); ++i) {
    const auto& c = m.classes(i);
    const bool scored = validated && i < m.validation().per_class_size();
    std::printf("  %2u %-18s F1 %s\n", c.id(), c.name().c_str(),
                scored ? score_or_na(m.validation().per_class(i).f1()).c_str() : "n/a");
  }
  return kExitOk;
}

}  // namespace primlabel::client::tools
