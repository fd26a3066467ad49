# Model files: LabelModel <-> primlabel.v1.Model (protobuf, no gRPC), checksummed.
find_package(ZLIB REQUIRED)
target_sources(primlabel_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/label_model.cpp)
target_link_libraries(primlabel_core PUBLIC primlabel_model_proto PRIVATE ZLIB::ZLIB)
