#pragma once
// primlabel.v1.Labeler: Label (streaming) and LabelCloud (unary) on raw messages and gRPC's
// callback API (see label_reactors.hpp), ListModels and GetModelMetadata.

#include "primlabel/rpc/auth.hpp"
#include "primlabel/service/service_environment.hpp"
#include "primlabel/v1/labeling.grpc.pb.h"

namespace primlabel::rpc {

using LabelerBase = v1::Labeler::WithRawCallbackMethod_Label<
    v1::Labeler::WithRawCallbackMethod_LabelCloud<v1::Labeler::Service>>;

class LabelerService final : public LabelerBase {
 public:
  LabelerService(const service::ServiceEnvironment& env, const TokenAuth& auth);

  grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* Label(
      grpc::CallbackServerContext* context) override;
  grpc::ServerUnaryReactor* LabelCloud(grpc::CallbackServerContext* context,
                                       const grpc::ByteBuffer* request,
                                       grpc::ByteBuffer* response) override;

  grpc::Status ListModels(grpc::ServerContext* context, const v1::ListModelsRequest* request,
                          v1::ListModelsResponse* response) override;
  grpc::Status GetModelMetadata(grpc::ServerContext* context,
                                const v1::GetModelMetadataRequest* request,
                                v1::ModelMetadata* response) override;

 private:
  const service::ServiceEnvironment& env_;
  const TokenAuth& auth_;
};

void fill_model_info(const service::ServedModel& model, v1::ModelInfo& info);

}  // namespace primlabel::rpc
