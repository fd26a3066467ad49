#include "primlabel/client/client.hpp"

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/support/byte_buffer.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <list>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>

#include "call_control.hpp"
#include "channel.hpp"
#include "health_wire.hpp"
#include "label_assembler.hpp"
#include "primlabel/v1/labeling.grpc.pb.h"
#include "primlabel/wire/packing.hpp"
#include "primlabel/wire/status_names.hpp"

namespace primlabel::client {

namespace {

using Clock = std::chrono::system_clock;

// The one option the server cannot check: it only ever sees scaled points.
void require_valid_units(const LabelOptions& o) {
  if (!(o.metres_per_unit > 0.0f) || !std::isfinite(o.metres_per_unit))
    throw std::invalid_argument("metres_per_unit must be finite and > 0, got " +
                                std::to_string(o.metres_per_unit));
}

v1::LabelRequest header_request(const PointCloud& cloud, const LabelOptions& o) {
  v1::LabelRequest request;
  v1::ScanHeader& header = *request.mutable_header();
  header.set_model(o.model);
  header.set_model_version(o.model_version);
  header.set_scan_id(o.scan_id);
  header.set_frame_id(o.frame_id);
  header.set_stamp_ns(o.stamp_ns);
  const Vec3f viewpoint = o.viewpoint.value_or(cloud.viewpoint.origin) * o.metres_per_unit;
  header.mutable_viewpoint()->set_x(viewpoint.x());
  header.mutable_viewpoint()->set_y(viewpoint.y());
  header.mutable_viewpoint()->set_z(viewpoint.z());
  v1::LabelOptions& options = *header.mutable_options();
  options.set_return_descriptors(o.descriptors);
  options.set_return_probabilities(o.probabilities);
  options.set_return_primitives(o.primitives);
  options.set_tabletop_only(o.tabletop_only);
  options.set_return_objects(o.objects);
  options.set_voxel_size(o.voxel_size);
  options.set_every_point(o.every_point);
  options.set_normal_radius(o.normal_radius);
  options.set_feature_radius(o.feature_radius);
  options.set_non_finite(o.reject_non_finite ? v1::NON_FINITE_REJECT : v1::NON_FINITE_DROP);
  options.set_response_chunk_points(o.response_chunk_points);
  header.mutable_layout()->set_normals(o.send_normals && cloud.has_normals());
  if (cloud.organized()) {  // a frame: lets a request naming no model find the camera's model
    header.mutable_layout()->set_width(cloud.width);
    header.mutable_layout()->set_height(cloud.height);
  }
  header.set_expected_points(cloud.size());
  return request;
}

// Runs `work` and adds the seconds it took to `total`; returns what `work` returns.
template <class Work>
decltype(auto) timed(double& total, Work&& work) {
  struct AddElapsed {
    double& total;
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    ~AddElapsed() {
      total += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
  } add{total};
  return work();
}

void fill_chunk(const PointCloud& cloud, const LabelOptions& o, std::size_t first,
                std::size_t count, v1::PointChunk& chunk) {
  if (o.metres_per_unit == 1.0f) {
    chunk.set_xyz(wire::pack_vec3(cloud.xyz, first, count));
  } else {
    std::vector<Vec3f> scaled(cloud.xyz.begin() + std::ptrdiff_t(first),
                              cloud.xyz.begin() + std::ptrdiff_t(first + count));
    for (Vec3f& p : scaled) p *= o.metres_per_unit;
    chunk.set_xyz(wire::pack_vec3(scaled, 0, count));
  }
  if (o.send_normals && cloud.has_normals())
    chunk.set_normals(wire::pack_vec3(cloud.normals, first, count));
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Errors

std::string status_code_name(grpc::StatusCode code) {
  return ::primlabel::wire::status_code_name(code);
}

std::string model_choice_name(v1::ModelChoice choice) {
  switch (choice) {
    case v1::MODEL_CHOICE_NAMED:
      return "named";
    case v1::MODEL_CHOICE_DOMAIN:
      return "domain";
    case v1::MODEL_CHOICE_DEFAULT:
      return "default";
    default:
      return "";
  }
}

std::string model_choice_text(const v1::LabelSummary& summary) {
  switch (summary.model_choice()) {
    case v1::MODEL_CHOICE_NAMED:
      return "named by the request";
    case v1::MODEL_CHOICE_DOMAIN:
      return "chosen by domain: " + summary.model_choice_reason();
    case v1::MODEL_CHOICE_DEFAULT:
      return "the default: " + summary.model_choice_reason();
    default:
      return "";
  }
}

std::string health_status_name(HealthStatus status) {
  switch (status) {
    case HealthStatus::kServing:
      return "SERVING";
    case HealthStatus::kNotServing:
      return "NOT_SERVING";
    case HealthStatus::kServiceUnknown:
      return "SERVICE_UNKNOWN";
    default:
      return "UNKNOWN";
  }
}

namespace {
std::string describe(grpc::StatusCode code, const std::string& message, int attempts) {
  std::string text = status_code_name(code) + ": " + message;
  if (attempts > 1) text += " (after " + std::to_string(attempts) + " attempts)";
  return text;
}
}  // namespace

ClientError::ClientError(grpc::StatusCode code, const std::string& message, int attempts)
    : std::runtime_error(describe(code, message, attempts)), code_(code), attempts_(attempts) {}

// ---------------------------------------------------------------------------------------------
// Asynchronous calls

struct CallHandle::State {
  CallControl control;
  mutable std::mutex mutex;
  mutable std::condition_variable finished;
  bool done = false;
};

void CallHandle::cancel() {
  if (state_) state_->control.cancel();
}
bool CallHandle::done() const {
  if (!state_) return true;
  std::lock_guard lock(state_->mutex);
  return state_->done;
}
void CallHandle::wait() const {
  if (!state_) return;
  std::unique_lock lock(state_->mutex);
  state_->finished.wait(lock, [&] { return state_->done; });
}

// ---------------------------------------------------------------------------------------------
// The client

struct Client::Impl {
  explicit Impl(const ClientOptions& options)
      : options(options),
        channel(make_channel(options)),
        labeler(v1::Labeler::NewStub(channel)),
        generic(channel) {}

  // Runs `attempt(context)` until it succeeds, fails with something other than UNAVAILABLE, the
  // attempts are used up or the deadline would pass during the backoff. Returns the attempts.
  template <class Attempt>
  int with_retries(std::chrono::milliseconds timeout, CallControl* control, Attempt&& attempt) {
    const auto deadline = Clock::now() + timeout;
    Backoff backoff(options.backoff);
    for (int n = 1;; ++n) {
      grpc::ClientContext context;
      context.set_deadline(deadline);
      if (!options.bearer_token.empty())
        context.AddMetadata("authorization", "Bearer " + options.bearer_token);
      if (control && !control->attach(&context))
        throw ClientError(grpc::StatusCode::CANCELLED, "cancelled", n - 1);
      grpc::Status status;
      try {
        status = attempt(context);
      } catch (const ProtocolError& e) {
        if (control) control->detach();
        throw ClientError(grpc::StatusCode::DATA_LOSS, e.what(), n);
      }
      if (control) control->detach();
      if (status.ok()) return n;
      if (status.error_code() == grpc::StatusCode::UNAVAILABLE && n < options.retry_attempts) {
        const auto delay = backoff.next();
        if (Clock::now() + delay < deadline) {
          const bool slept =
              control ? control->sleep_for(delay) : (std::this_thread::sleep_for(delay), true);
          if (!slept) throw ClientError(grpc::StatusCode::CANCELLED, "cancelled", n);
          continue;
        }
      }
      throw ClientError(status.error_code(), status.error_message(), n);
    }
  }

  std::chrono::milliseconds timeout_of(const LabelOptions& o) const {
    return o.deadline.value_or(options.deadline);
  }

  LabelResult label_stream(const PointCloud& cloud, const LabelOptions& o,
                           const std::function<void(std::size_t, std::size_t)>& on_progress,
                           CallControl* control) {
    require_valid_units(o);
    const std::size_t chunk_points = std::max<std::size_t>(1, o.chunk_points);
    LabelResult result;
    result.attempts = with_retries(timeout_of(o), control, [&](grpc::ClientContext& context) {
      ClientSeconds seconds;
      LabelAssembler assembler = timed(seconds.decode, [&] {
        return LabelAssembler(cloud.size(), o.descriptors, o.probabilities, o.primitives,
                              o.objects);
      });
      auto stream = labeler->Label(&context);
      // Writes stop at the first failure: the server has ended the call, Finish says why.
      const v1::LabelRequest header =
          timed(seconds.encode, [&] { return header_request(cloud, o); });
      bool writing = timed(seconds.send, [&] { return stream->Write(header); });
      v1::LabelRequest request;
      for (std::size_t first = 0; writing && first < cloud.size(); first += chunk_points) {
        const std::size_t count = std::min(chunk_points, cloud.size() - first);
        timed(seconds.encode,
              [&] { fill_chunk(cloud, o, first, count, *request.mutable_chunk()); });
        writing = timed(seconds.send, [&] { return stream->Write(request); });
        if (writing && on_progress) on_progress(first + count, cloud.size());
      }
      if (writing) {
        v1::LabelRequest end;
        end.mutable_end();
        timed(seconds.send, [&] {
          if (stream->Write(end)) stream->WritesDone();
        });
      }
      std::optional<v1::LabelSummary> summary;
      v1::LabelResponse response;
      try {
        while (timed(seconds.receive, [&] { return stream->Read(&response); })) {
          timed(seconds.decode, [&] {
            if (response.has_chunk()) {
              assembler.add(response.chunk());
            } else if (response.has_summary()) {
              summary = std::move(*response.mutable_summary());
            }
          });
        }
      } catch (const ProtocolError&) {
        context.TryCancel();
        stream->Finish();
        throw;
      }
      grpc::Status status = timed(seconds.receive, [&] { return stream->Finish(); });
      if (!status.ok()) return status;
      if (!summary) throw ProtocolError("the server closed the stream without a summary");
      result = timed(seconds.decode, [&] { return assembler.finish(*summary); });
      result.client_seconds = seconds;
      return status;
    });
    return result;
  }

  LabelResult label_unary(const PointCloud& cloud, const LabelOptions& o, CallControl* control) {
    require_valid_units(o);
    ClientSeconds seconds;
    v1::LabelCloudRequest request;
    timed(seconds.encode, [&] {
      *request.mutable_header() = header_request(cloud, o).header();
      fill_chunk(cloud, o, 0, cloud.size(), *request.mutable_points());
    });
    LabelResult result;
    result.attempts = with_retries(timeout_of(o), control, [&](grpc::ClientContext& context) {
      v1::LabelCloudResponse response;
      seconds.receive = 0;
      seconds.decode = 0;
      grpc::Status status =
          timed(seconds.receive, [&] { return labeler->LabelCloud(&context, request, &response); });
      if (!status.ok()) return status;
      result = timed(seconds.decode, [&] {
        LabelAssembler assembler(cloud.size(), o.descriptors, o.probabilities, o.primitives,
                                 o.objects);
        assembler.add(response.result());
        return assembler.finish(response.summary());
      });
      result.client_seconds = seconds;
      return status;
    });
    return result;
  }

  // Joins the worker threads whose calls have finished.
  void reap_workers(bool all) {
    std::list<Worker> finished;
    {
      std::lock_guard lock(workers_mutex);
      for (auto it = workers.begin(); it != workers.end();) {
        bool done;
        {
          std::lock_guard state_lock(it->state->mutex);
          done = it->state->done;
        }
        if (all || done) {
          finished.splice(finished.end(), workers, it++);
        } else {
          ++it;
        }
      }
    }
    for (auto& worker : finished) worker.thread.join();
  }

  ClientOptions options;
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<v1::Labeler::Stub> labeler;
  grpc::GenericStub generic;

  struct Worker {
    std::thread thread;
    std::shared_ptr<CallHandle::State> state;
  };
  std::mutex workers_mutex;
  std::list<Worker> workers;
};

Client::Client(ClientOptions options)
    : options_(std::move(options)), impl_(std::make_unique<Impl>(options_)) {}

Client::~Client() {
  {
    std::lock_guard lock(impl_->workers_mutex);
    for (auto& worker : impl_->workers) worker.state->control.cancel();
  }
  impl_->reap_workers(/*all=*/true);
}

LabelResult Client::label(const PointCloud& cloud, const LabelOptions& options,
                          const std::function<void(std::size_t, std::size_t)>& on_progress) {
  return impl_->label_stream(cloud, options, on_progress, nullptr);
}

LabelResult Client::label_unary(const PointCloud& cloud, const LabelOptions& options) {
  return impl_->label_unary(cloud, options, nullptr);
}

CallHandle Client::label_async(PointCloud cloud, LabelOptions options, LabelCallback done,
                               bool unary) {
  impl_->reap_workers(/*all=*/false);
  CallHandle handle;
  handle.state_ = std::make_shared<CallHandle::State>();
  auto state = handle.state_;
  std::lock_guard lock(impl_->workers_mutex);
  impl_->workers.push_back(
      {std::thread([this, state, cloud = std::move(cloud), options = std::move(options),
                    done = std::move(done), unary] {
         CallStatus status;
         LabelResult result;
         try {
           result = unary ? impl_->label_unary(cloud, options, &state->control)
                          : impl_->label_stream(cloud, options, {}, &state->control);
           status.attempts = result.attempts;
         } catch (const ClientError& e) {
           status = {e.code(), e.what(), e.attempts()};
         } catch (const std::exception& e) {
           status = {grpc::StatusCode::INTERNAL, e.what(), 1};
         }
         if (done) done(std::move(status), std::move(result));
         std::lock_guard state_lock(state->mutex);
         state->done = true;
         state->finished.notify_all();
       }),
       state});
  return handle;
}

std::vector<v1::ModelInfo> Client::list_models() {
  v1::ListModelsResponse response;
  impl_->with_retries(options_.deadline, nullptr, [&](grpc::ClientContext& context) {
    return impl_->labeler->ListModels(&context, v1::ListModelsRequest{}, &response);
  });
  return {response.models().begin(), response.models().end()};
}

v1::ModelMetadata Client::model_metadata(const std::string& model, const std::string& version) {
  v1::GetModelMetadataRequest request;
  request.set_model(model);
  request.set_version(version);
  v1::ModelMetadata response;
  impl_->with_retries(options_.deadline, nullptr, [&](grpc::ClientContext& context) {
    return impl_->labeler->GetModelMetadata(&context, request, &response);
  });
  return response;
}

HealthStatus Client::health(const std::string& service) {
  std::uint32_t status = 0;
  impl_->with_retries(options_.deadline, nullptr, [&](grpc::ClientContext& context) {
    const std::string bytes = health_wire::encode_request(service);
    grpc::Slice slice(bytes);
    grpc::ByteBuffer request(&slice, 1);
    grpc::ByteBuffer response;
    std::promise<grpc::Status> finished;
    impl_->generic.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(),
                             &request, &response,
                             [&](grpc::Status s) { finished.set_value(std::move(s)); });
    grpc::Status result = finished.get_future().get();
    if (!result.ok()) return result;
    std::vector<grpc::Slice> slices;
    std::string body;
    if (response.Dump(&slices).ok())
      for (const auto& s : slices) body.append(reinterpret_cast<const char*>(s.begin()), s.size());
    const auto decoded = health_wire::decode_status(body);
    if (!decoded) throw ProtocolError("malformed grpc.health.v1 response");
    status = *decoded;
    return result;
  });
  return status <= 3 ? static_cast<HealthStatus>(status) : HealthStatus::kUnknown;
}

}  // namespace primlabel::client
