#pragma once
// primlabel.v1.ModelAdmin: load, unload and rescan models; needs the bearer token when one is
// configured, and is refused without one unless --insecure-admin allows it. An unload lasts
// until the next LoadModel of that model or ReloadModels (the periodic scan does not undo it).
// Health and metrics follow the registry through its observer, not through this service.

#include "primlabel/rpc/auth.hpp"
#include "primlabel/service/service_environment.hpp"
#include "primlabel/v1/labeling.grpc.pb.h"

namespace primlabel::rpc {

class AdminService final : public v1::ModelAdmin::Service {
 public:
  AdminService(const service::ServiceEnvironment& env, const TokenAuth& auth)
      : env_(env), auth_(auth) {}

  grpc::Status LoadModel(grpc::ServerContext* context, const v1::LoadModelRequest* request,
                         v1::LoadModelResponse* response) override;
  grpc::Status UnloadModel(grpc::ServerContext* context, const v1::UnloadModelRequest* request,
                           v1::UnloadModelResponse* response) override;
  grpc::Status ReloadModels(grpc::ServerContext* context, const v1::ReloadModelsRequest* request,
                            v1::ReloadModelsResponse* response) override;

 private:
  const service::ServiceEnvironment& env_;
  const TokenAuth& auth_;
};

}  // namespace primlabel::rpc
