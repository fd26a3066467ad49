// Uses the installed package as a robot's software would: estimates normals with primlabel::core,
// then labels the cloud through primlabel::client against an address where nothing listens.
// Exit 0 when the call fails cleanly with UNAVAILABLE (or DEADLINE_EXCEEDED), 1 otherwise.
#include <chrono>
#include <cstdio>
#include <exception>

#include "primlabel/client/client.hpp"
#include "primlabel/geometry/normals.hpp"
#include "primlabel/geometry/point_cloud.hpp"

int main() {
  primlabel::PointCloud cloud;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) cloud.xyz.emplace_back(0.01f * i, 0.01f * j, 0.0f);
  cloud.width = cloud.size();
  primlabel::NormalOptions normal_options;
  normal_options.neighborhood = primlabel::Neighborhood::Knn(5);
  const primlabel::NormalStats stats = primlabel::estimate_normals(cloud, normal_options);
  std::printf("normals: %zu of %zu points\n", stats.estimated, cloud.size());
  if (stats.estimated != cloud.size()) return 1;

  primlabel::client::ClientOptions options;
  options.address = "127.0.0.1:1";
  options.deadline = std::chrono::milliseconds(5'000);
  options.retry_attempts = 2;
  primlabel::client::Client client(options);
  primlabel::client::LabelOptions label_options;
  label_options.send_normals = true;
  try {
    primlabel::client::LabelResult result = client.label(cloud, label_options);
    std::printf("unexpected: %zu labels from 127.0.0.1:1\n", result.size());
    return 1;
  } catch (const primlabel::client::ClientError& e) {
    std::printf("expected failure: %s after %d attempt(s): %s\n",
                primlabel::client::status_code_name(e.code()).c_str(), e.attempts(), e.what());
    const bool clean = e.code() == grpc::StatusCode::UNAVAILABLE ||
                       e.code() == grpc::StatusCode::DEADLINE_EXCEEDED;
    return clean ? 0 : 1;
  } catch (const std::exception& e) {
    std::printf("unexpected exception: %s\n", e.what());
    return 1;
  }
}
