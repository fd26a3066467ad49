#include "labeler_service.hpp"

#include <grpcpp/support/method_handler.h>

#include "label_stream.hpp"
#include "registry_status.hpp"
#include "request_record.hpp"

namespace primlabel::server {

namespace {

// Method indices in labeling.proto's Labeler service.
constexpr int kLabelMethod = 0;
constexpr int kLabelCloudMethod = 1;

using RawHandler =
    grpc::internal::BidiStreamingHandler<LabelerService, grpc::ByteBuffer, grpc::ByteBuffer>;

}  // namespace

LabelerService::LabelerService(const ServiceEnvironment& env) : env_(env) {
  // The labeling methods read raw bytes (a malformed message gets a precise INVALID_ARGUMENT
  // instead of looking like the end of the stream). LabelCloud stays unary on the wire.
  MarkMethodStreamed(
      kLabelMethod,
      new RawHandler(
          [](LabelerService* service, grpc::ServerContext* context, RawStream* stream) {
            return serve_label_stream(service->env_, *context, *stream);
          },
          this));
  MarkMethodStreamed(
      kLabelCloudMethod,
      new RawHandler(
          [](LabelerService* service, grpc::ServerContext* context, RawStream* stream) {
            return serve_label_cloud(service->env_, *context, *stream);
          },
          this));
}

void fill_model_info(const ServedModel& model, v1::ModelInfo& info) {
  const ModelEntry& entry = *model.served;
  info.set_name(model.name);
  info.set_version(entry.version);
  for (const std::string& version : model.versions) info.add_loaded_versions(version);
  info.set_kind(entry.metadata.kind());
  info.set_descriptor_kind(entry.metadata.features().descriptor_kind());
  info.set_classes(static_cast<std::uint32_t>(entry.metadata.classes_size()));
  info.set_is_default(model.is_default);
  info.set_validation_accuracy(entry.metadata.validation().accuracy());
  info.set_loaded_unix_ms(entry.loaded_unix_ms);
}

grpc::Status LabelerService::ListModels(grpc::ServerContext* context, const v1::ListModelsRequest*,
                                        v1::ListModelsResponse* response) {
  RequestRecord record("ListModels", *env_.metrics);
  if (grpc::Status status = env_.auth->check(*context, false); !status.ok())
    return record.finish(status);
  for (const ServedModel& model : env_.registry->list())
    fill_model_info(model, *response->add_models());
  return record.finish(grpc::Status::OK);
}

grpc::Status LabelerService::GetModelMetadata(grpc::ServerContext* context,
                                              const v1::GetModelMetadataRequest* request,
                                              v1::ModelMetadata* response) {
  RequestRecord record("GetModelMetadata", *env_.metrics);
  record.model = request->model();
  if (grpc::Status status = env_.auth->check(*context, false); !status.ok())
    return record.finish(status);
  try {
    const auto entry = env_.registry->resolve(request->model(), request->version());
    record.model = entry->name;
    record.version = entry->version;
    record.model_resolved = true;
    *response = entry->metadata;
  } catch (const RegistryError& error) {
    return record.finish(registry_status(error));
  }
  return record.finish(grpc::Status::OK);
}

}  // namespace primlabel::server
