#pragma once
// primlabel.v1.Labeler: Label (streaming) and LabelCloud (unary) on raw messages (see
// label_stream.hpp), ListModels and GetModelMetadata.

#include "primlabel/v1/labeling.grpc.pb.h"
#include "service_environment.hpp"

namespace primlabel::server {

class LabelerService final : public v1::Labeler::Service {
 public:
  explicit LabelerService(const ServiceEnvironment& env);

  grpc::Status ListModels(grpc::ServerContext* context, const v1::ListModelsRequest* request,
                          v1::ListModelsResponse* response) override;
  grpc::Status GetModelMetadata(grpc::ServerContext* context,
                                const v1::GetModelMetadataRequest* request,
                                v1::ModelMetadata* response) override;

 private:
  const ServiceEnvironment& env_;
};

void fill_model_info(const ServedModel& model, v1::ModelInfo& info);

}  // namespace primlabel::server
