#include "label_stream.hpp"

#include <chrono>
#include <optional>

#include "label_job.hpp"
#include "label_response.hpp"
#include "message_codec.hpp"
#include "request_record.hpp"
#include "scan_assembler.hpp"

namespace primlabel::server {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

grpc::Status invalid(const std::string& message) {
  return {grpc::StatusCode::INVALID_ARGUMENT, message};
}

grpc::Status client_gone(grpc::ServerContext& context, const char* while_doing) {
  if (std::chrono::system_clock::now() > context.deadline())
    return {grpc::StatusCode::DEADLINE_EXCEEDED, std::string("the deadline passed ") + while_doing};
  return {grpc::StatusCode::CANCELLED, std::string("the client went away ") + while_doing};
}

const char* kind_name(v1::LabelRequest::KindCase kind) {
  switch (kind) {
    case v1::LabelRequest::kHeader:
      return "a ScanHeader";
    case v1::LabelRequest::kChunk:
      return "a PointChunk";
    case v1::LabelRequest::kEnd:
      return "an EndOfScan";
    default:
      return "an empty LabelRequest";
  }
}

ScanLimits limits_of(const ServerConfig& config) {
  return ScanLimits{config.max_points, config.max_request_bytes};
}

// Admission and planning, common to both methods: the ticket is taken at header time, before
// any point is buffered.
grpc::Status start_request(const ServiceEnvironment& env, const v1::ScanHeader& header,
                           RequestRecord& record, LabelPlan& plan,
                           std::optional<Admission::Ticket>& ticket) {
  record.scan_id = header.scan_id();
  record.model = header.model();
  if (grpc::Status status = check_header(header, limits_of(*env.config)); !status.ok())
    return status;
  if (grpc::Status status = plan_labeling(header, env, plan); !status.ok()) return status;
  record.model = plan.entry->name;
  record.version = plan.entry->version;
  record.model_resolved = true;
  ticket = env.admission->try_admit();
  if (!ticket) return server_busy(*env.admission);
  return grpc::Status::OK;
}

// A draining server, or a caller without a valid token, is turned away before anything is read.
grpc::Status may_start(const ServiceEnvironment& env, grpc::ServerContext& context) {
  if (env.draining->load()) return shutting_down();
  return env.auth->check(context, false);
}

}  // namespace

grpc::Status serve_label_stream(const ServiceEnvironment& env, grpc::ServerContext& context,
                                RawStream& stream) {
  RequestRecord record("Label", *env.metrics);
  if (grpc::Status status = may_start(env, context); !status.ok()) return record.finish(status);

  // State 1: the header.
  grpc::ByteBuffer buffer;
  v1::LabelRequest request;
  if (!stream.Read(&buffer)) {
    if (context.IsCancelled()) return record.finish(client_gone(context, "before the header"));
    return record.finish(invalid("the stream ended before a ScanHeader"));
  }
  const Clock::time_point receive_start = Clock::now();
  if (!parse_message(buffer, request))
    return record.finish(invalid("message 1 is not a valid LabelRequest"));
  if (!request.has_header())
    return record.finish(invalid(std::string("message 1 must be a ScanHeader, got ") +
                                 kind_name(request.kind_case())));
  const v1::ScanHeader header = request.header();
  LabelPlan plan;
  std::optional<Admission::Ticket> ticket;
  if (grpc::Status status = start_request(env, header, record, plan, ticket); !status.ok())
    return record.finish(status);

  // State 2: chunks until EndOfScan or half-close.
  ScanAssembler assembler(header, limits_of(*env.config));
  for (std::uint64_t index = 2;; ++index) {
    if (!stream.Read(&buffer)) {
      if (context.IsCancelled()) return record.finish(client_gone(context, "while sending points"));
      break;  // half-close ends the scan
    }
    if (!parse_message(buffer, request))
      return record.finish(
          invalid("message " + std::to_string(index) + " is not a valid LabelRequest"));
    if (request.has_end()) break;
    if (!request.has_chunk())
      return record.finish(invalid("message " + std::to_string(index) + " is " +
                                   kind_name(request.kind_case()) +
                                   "; expected a PointChunk or EndOfScan"));
    grpc::Status added = assembler.add(request.chunk());
    record.points = assembler.points();
    if (!added.ok()) return record.finish(added);
  }
  record.points = assembler.points();
  record.dropped_non_finite = assembler.non_finite();
  if (grpc::Status status = assembler.finish(); !status.ok()) return record.finish(status);
  record.stages.receive = seconds_since(receive_start);

  // State 3: label.
  pipeline::LabelingResult result;
  if (grpc::Status status =
          run_labeling(context, env, *ticket, plan, assembler.cloud(), result, record);
      !status.ok())
    return record.finish(status);
  assembler.cloud() = PointCloud{};  // the points are no longer needed

  // State 4: chunks, then the summary.
  const Clock::time_point send_start = Clock::now();
  const LabelResponder responder(result, header.options().response_chunk_points(),
                                 env.config->response_chunk_bytes);
  v1::LabelResponse response;
  for (std::uint64_t chunk = 0; chunk < responder.chunk_count(); ++chunk) {
    response.Clear();
    responder.fill_chunk(chunk, *response.mutable_chunk());
    if (!stream.Write(serialize_message(response)))
      return record.finish(client_gone(context, "while receiving labels"));
  }
  record.stages.send = seconds_since(send_start);
  response.Clear();
  fill_summary(record, *plan.entry, result, *response.mutable_summary());
  if (!stream.Write(serialize_message(response)))
    return record.finish(client_gone(context, "before the summary"));
  return record.finish(grpc::Status::OK);
}

grpc::Status serve_label_cloud(const ServiceEnvironment& env, grpc::ServerContext& context,
                               RawStream& stream) {
  RequestRecord record("LabelCloud", *env.metrics);
  if (grpc::Status status = may_start(env, context); !status.ok()) return record.finish(status);
  grpc::ByteBuffer buffer;
  if (!stream.Read(&buffer)) return record.finish(invalid("no LabelCloudRequest was sent"));
  const Clock::time_point receive_start = Clock::now();
  v1::LabelCloudRequest request;
  if (!parse_message(buffer, request))
    return record.finish(invalid("the request is not a valid LabelCloudRequest"));
  if (!request.has_header()) return record.finish(invalid("the request has no header"));
  LabelPlan plan;
  std::optional<Admission::Ticket> ticket;
  if (grpc::Status status = start_request(env, request.header(), record, plan, ticket);
      !status.ok())
    return record.finish(status);
  ScanAssembler assembler(request.header(), limits_of(*env.config));
  grpc::Status added = assembler.add(request.points());
  record.points = assembler.points();
  record.dropped_non_finite = assembler.non_finite();
  if (!added.ok()) return record.finish(added);
  if (grpc::Status status = assembler.finish(); !status.ok()) return record.finish(status);
  request.Clear();
  record.stages.receive = seconds_since(receive_start);

  pipeline::LabelingResult result;
  if (grpc::Status status =
          run_labeling(context, env, *ticket, plan, assembler.cloud(), result, record);
      !status.ok())
    return record.finish(status);

  const Clock::time_point send_start = Clock::now();
  const LabelResponder responder(result, 0, std::uint64_t(-1));
  const std::uint64_t bytes = responder.bytes_per_point() * result.labels.size();
  if (bytes + 4096 > std::uint64_t(env.config->max_message_bytes))
    return record.finish(
        {grpc::StatusCode::RESOURCE_EXHAUSTED, "the response would take " + std::to_string(bytes) +
                                                   " bytes, over the server's message limit of " +
                                                   std::to_string(env.config->max_message_bytes) +
                                                   "; use the streaming Label RPC"});
  v1::LabelCloudResponse response;
  responder.fill_range(0, result.labels.size(), *response.mutable_result());
  record.stages.send = 0;
  fill_summary(record, *plan.entry, result, *response.mutable_summary());
  if (!stream.Write(serialize_message(response)))
    return record.finish(client_gone(context, "while receiving labels"));
  record.stages.send = seconds_since(send_start);
  return record.finish(grpc::Status::OK);
}

}  // namespace primlabel::server
