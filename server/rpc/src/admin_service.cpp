#include "primlabel/rpc/admin_service.hpp"

#include "primlabel/rpc/auth.hpp"
#include "primlabel/rpc/grpc_status.hpp"
#include "primlabel/rpc/labeler_service.hpp"
#include "primlabel/service/registry_error.hpp"
#include "primlabel/service/request_record.hpp"

namespace primlabel::rpc {

grpc::Status AdminService::LoadModel(grpc::ServerContext* context,
                                     const v1::LoadModelRequest* request,
                                     v1::LoadModelResponse* response) {
  service::RequestRecord record("LoadModel", *env_.metrics);
  record.model = request->model();
  if (auto refused = auth_.check(*context, true))
    return finish_request(record, to_grpc_status(*refused));
  try {
    const auto entry = env_.registry->load(request->model(), request->version());
    record.version = entry->version;
    record.model_resolved = true;
    env_.metrics->reloads(1, 0);
  } catch (const service::RegistryError& error) {
    if (error.kind() == service::RegistryError::Kind::kLoadFailed) env_.metrics->reloads(0, 1);
    return finish_request(record, to_grpc_status(service::registry_error(error)));
  }
  for (const service::ServedModel& model : env_.registry->list())
    if (model.name == request->model()) fill_model_info(model, *response->mutable_model());
  return finish_request(record, grpc::Status::OK);
}

grpc::Status AdminService::UnloadModel(grpc::ServerContext* context,
                                       const v1::UnloadModelRequest* request,
                                       v1::UnloadModelResponse* response) {
  service::RequestRecord record("UnloadModel", *env_.metrics);
  record.model = request->model();
  record.version = request->version();
  if (auto refused = auth_.check(*context, true))
    return finish_request(record, to_grpc_status(*refused));
  try {
    response->set_unloaded_versions(env_.registry->unload(request->model(), request->version()));
  } catch (const service::RegistryError& error) {
    return finish_request(record, to_grpc_status(service::registry_error(error)));
  }
  return finish_request(record, grpc::Status::OK);
}

grpc::Status AdminService::ReloadModels(grpc::ServerContext* context,
                                        const v1::ReloadModelsRequest*,
                                        v1::ReloadModelsResponse* response) {
  service::RequestRecord record("ReloadModels", *env_.metrics);
  if (auto refused = auth_.check(*context, true))
    return finish_request(record, to_grpc_status(*refused));
  try {
    // Unloads last until this explicit reload, which brings their versions back.
    const service::ReloadReport report = env_.registry->reload();
    env_.metrics->reloads(report.loaded, report.failed);
    response->set_loaded(report.loaded);
    response->set_failed(report.failed);
    for (const std::string& error : report.errors) response->add_errors(error);
  } catch (const service::RegistryError& error) {
    return finish_request(record, to_grpc_status(service::registry_error(error)));
  }
  for (const service::ServedModel& model : env_.registry->list())
    fill_model_info(model, *response->add_models());
  return finish_request(record, grpc::Status::OK);
}

}  // namespace primlabel::rpc
