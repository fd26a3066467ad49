#include "primlabel/rpc/labeler_service.hpp"

#include "label_reactors.hpp"
#include "primlabel/rpc/auth.hpp"
#include "primlabel/rpc/grpc_status.hpp"
#include "primlabel/service/registry_error.hpp"
#include "primlabel/service/request_record.hpp"

namespace primlabel::rpc {

LabelerService::LabelerService(const service::ServiceEnvironment& env, const TokenAuth& auth)
    : env_(env), auth_(auth) {}

grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* LabelerService::Label(
    grpc::CallbackServerContext* context) {
  return start_label_reactor(env_, auth_, context);
}

grpc::ServerUnaryReactor* LabelerService::LabelCloud(grpc::CallbackServerContext* context,
                                                     const grpc::ByteBuffer* request,
                                                     grpc::ByteBuffer* response) {
  return start_label_cloud_reactor(env_, auth_, context, request, response);
}

void fill_model_info(const service::ServedModel& model, v1::ModelInfo& info) {
  const service::ModelEntry& entry = *model.served;
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
  service::RequestRecord record("ListModels", *env_.metrics);
  if (auto refused = auth_.check(*context, false))
    return finish_request(record, to_grpc_status(*refused));
  for (const service::ServedModel& model : env_.registry->list())
    fill_model_info(model, *response->add_models());
  return finish_request(record, grpc::Status::OK);
}

grpc::Status LabelerService::GetModelMetadata(grpc::ServerContext* context,
                                              const v1::GetModelMetadataRequest* request,
                                              v1::ModelMetadata* response) {
  service::RequestRecord record("GetModelMetadata", *env_.metrics);
  record.model = request->model();
  if (auto refused = auth_.check(*context, false))
    return finish_request(record, to_grpc_status(*refused));
  try {
    const auto entry = env_.registry->resolve(request->model(), request->version());
    record.model = entry->name;
    record.version = entry->version;
    record.model_resolved = true;
    *response = entry->metadata;
  } catch (const service::RegistryError& error) {
    return finish_request(record, to_grpc_status(service::registry_error(error)));
  }
  return finish_request(record, grpc::Status::OK);
}

}  // namespace primlabel::rpc
