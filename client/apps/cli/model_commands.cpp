// health, models and info: small reads of the server's state, printed for people on stdout.

#include <cstdio>

#include "commands.hpp"
#include "exit_codes.hpp"

namespace primlabel::client::tools {

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
  for (const auto& m : models) {
    std::string loaded;
    for (const auto& v : m.loaded_versions()) loaded += (loaded.empty() ? "" : ",") + v;
    std::printf("%-24s %-20s %7u %8.3f %s%s\n", m.name().c_str(), m.version().c_str(), m.classes(),
                m.validation_accuracy(), loaded.c_str(), m.is_default() ? " (default)" : "");
  }
  if (models.empty()) std::fprintf(stderr, "primlabel: the server serves no models\n");
  return kExitOk;
}

int run_info(Client& client, const std::string& model, const std::string& version) {
  const v1::ModelMetadata m = client.model_metadata(model, version);
  std::printf("model      %s\nversion    %s\nkind       %s\n", m.name().c_str(),
              m.version().c_str(), v1::ModelKind_Name(m.kind()).c_str());
  std::printf("file       %s (crc32 %08x)\n", m.path().c_str(), m.model_crc32());
  std::printf("created    %lld by %s\n", static_cast<long long>(m.created_unix_ms()),
              m.created_by().c_str());
  const auto& f = m.features();
  std::printf(
      "features   %s, %u values; normal radius %g (k %u); feature radius %g (k %u); "
      "voxel %g; radii overridable: %s\n",
      v1::Descriptor_Name(f.descriptor_kind()).c_str(), f.descriptor_dim(), f.normal_radius(),
      f.normal_k(), f.feature_radius(), f.feature_k(), f.voxel_size(),
      f.radii_overridable() ? "yes" : "no");
  std::printf("graph      k %u, radius %g\n", m.graph().k(), m.graph().radius());
  std::printf("validation %.4f accuracy on %llu points\n", m.validation().accuracy(),
              static_cast<unsigned long long>(m.validation().points()));
  std::printf("classes    (probability columns in this order)\n");
  for (int i = 0; i < m.classes_size(); ++i) {
    const auto& c = m.classes(i);
    const double f1 = i < m.validation().per_class_size() ? m.validation().per_class(i).f1() : 0;
    std::printf("  %2u %-18s F1 %.3f\n", c.id(), c.name().c_str(), f1);
  }
  return kExitOk;
}

}  // namespace primlabel::client::tools
