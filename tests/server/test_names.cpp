// The names the server and the clients share: gRPC status codes (one table in
// primlabel/wire/status_names.hpp) and the request stages (one table in stage_times.hpp).

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "primlabel/ops/stage_times.hpp"
#include "primlabel/wire/status_names.hpp"

namespace primlabel::ops {
namespace {

TEST(SharedNames, StatusCodesHaveTheirCanonicalNames) {
  EXPECT_EQ(wire::status_code_name(grpc::StatusCode::OK), "OK");
  EXPECT_EQ(wire::status_code_name(grpc::StatusCode::DEADLINE_EXCEEDED), "DEADLINE_EXCEEDED");
  EXPECT_EQ(wire::status_code_name(grpc::StatusCode::RESOURCE_EXHAUSTED), "RESOURCE_EXHAUSTED");
  EXPECT_EQ(wire::status_code_name(grpc::StatusCode::UNAVAILABLE), "UNAVAILABLE");
  EXPECT_EQ(wire::status_code_name(grpc::StatusCode::UNAUTHENTICATED), "UNAUTHENTICATED");
  // One name per code, none empty.
  std::set<std::string> names;
  for (int code = 0; code <= 16; ++code)
    names.insert(wire::status_code_name(static_cast<grpc::StatusCode>(code)));
  EXPECT_EQ(names.size(), 17u);
  EXPECT_EQ(names.count(""), 0u);
  // A code the table does not know is not passed off as another one.
  EXPECT_EQ(wire::status_code_name(static_cast<grpc::StatusCode>(42)), "STATUS_42");
}

TEST(SharedNames, EachStageNamesItsOwnField) {
  std::set<std::string> names;
  for (const StageField& stage : kStages) {
    names.insert(stage.name);
    StageTimes times;
    times.*stage.seconds = 1.5;
    int set = 0;
    for (const StageField& other : kStages) set += (times.*other.seconds == 1.5);
    EXPECT_EQ(set, 1) << stage.name;
  }
  EXPECT_EQ(names, (std::set<std::string>{"receive", "prefilter", "normals", "features",
                                          "inference", "primitives", "send"}));
  EXPECT_STREQ(kStages.front().name, "receive");  // pipeline order: logs and responses read it
  EXPECT_STREQ(kStages.back().name, "send");
}

}  // namespace
}  // namespace primlabel::ops
