// The client library: packed arrays, backoff, reassembly checks, and every call against the
// in-process fake server (retries, validation, tokens, async, health).

#include <gtest/gtest.h>

#include <functional>
#include <future>
#include <set>

#include "fake_labeler.hpp"
#include "health_wire.hpp"
#include "label_assembler.hpp"
#include "primlabel/client/backoff.hpp"
#include "primlabel/client/client.hpp"
#include "primlabel/wire/packing.hpp"

namespace primlabel {
namespace {

using client::Client;
using client::ClientError;
using client::ClientOptions;
using client::LabelOptions;
using test::FakeServer;

// Points whose fake labels are i % 7 (the fake labels a point round(x)).
PointCloud labeled_line(std::size_t n) {
  PointCloud cloud;
  cloud.resize_unorganized(n);
  for (std::size_t i = 0; i < n; ++i) cloud.xyz[i] = Vec3f(float(i % 7), 0.5f * i, -1.0f);
  return cloud;
}

LabelOptions label_options(std::function<void(LabelOptions&)> set) {
  LabelOptions options;
  set(options);
  return options;
}

ClientOptions fast_options(const std::string& address) {
  ClientOptions options;
  options.address = address;
  options.deadline = std::chrono::seconds(20);
  options.backoff.initial = std::chrono::milliseconds(10);
  options.backoff.max = std::chrono::milliseconds(40);
  return options;
}

// ---------------------------------------------------------------------------------------------
// Wire format

TEST(ClientWire, PacksLittleEndianFloatsPointMajor) {
  const std::vector<Vec3f> points{{1.0f, -2.0f, 0.5f}, {3.0f, 4.0f, 5.0f}};
  const std::string bytes = wire::pack_vec3(points, 0, 2);
  ASSERT_EQ(bytes.size(), 24u);
  // 1.0f = 0x3F800000, least significant byte first.
  EXPECT_EQ(bytes.substr(0, 4), std::string("\x00\x00\x80\x3F", 4));
  EXPECT_EQ(bytes.substr(4, 4), std::string("\x00\x00\x00\xC0", 4));  // -2.0f
  const auto back = wire::unpack_vec3<Vec3f>(bytes);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0], points[0]);
  EXPECT_EQ(back[1], points[1]);
  EXPECT_EQ(wire::unpack_vec3<Vec3f>(wire::pack_vec3(points, 1, 1))[0], points[1]);
}

TEST(ClientWire, RejectsTruncatedXyzAndRangesPastTheEnd) {
  EXPECT_THROW(wire::unpack_vec3<Vec3f>(std::string(13, '\0')), std::invalid_argument);
  std::vector<Vec3f> one(1, Vec3f::Zero());
  EXPECT_THROW(wire::pack_vec3(one, 1, 1), std::out_of_range);
}

TEST(ClientWire, Uint32AndNanRoundTrip) {
  const std::vector<std::uint32_t> labels{0, 1, 0xDEADBEEF};
  const std::string bytes = wire::pack_u32(labels.data(), labels.size());
  EXPECT_EQ(bytes.substr(8, 4), std::string("\xEF\xBE\xAD\xDE", 4));
  std::vector<std::uint32_t> back(3);
  wire::unpack_u32(bytes, back.data());
  EXPECT_EQ(back, labels);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  float out = 0;
  wire::unpack_f32(wire::pack_f32(&nan, 1), &out);
  EXPECT_TRUE(std::isnan(out));
}

TEST(ClientHealthWire, EncodesServiceAndDecodesStatus) {
  EXPECT_EQ(client::health_wire::encode_request(""), "");
  EXPECT_EQ(client::health_wire::encode_request("ab"), std::string("\x0A\x02"
                                                                   "ab"));
  EXPECT_EQ(client::health_wire::decode_status(std::string("\x08\x01", 2)), 1u);
  EXPECT_EQ(client::health_wire::decode_status(""), 0u);  // proto3 default: UNKNOWN
  EXPECT_EQ(client::health_wire::decode_status(std::string("\x12\x01x\x08\x02", 5)), 2u);
  EXPECT_FALSE(client::health_wire::decode_status(std::string("\x08", 1)).has_value());
}

// ---------------------------------------------------------------------------------------------
// Backoff

TEST(ClientBackoff, NominalScheduleDoublesUpToTheCap) {
  client::Backoff backoff(
      {std::chrono::milliseconds(200), 2.0, std::chrono::milliseconds(5000), 0.0});
  std::vector<long> delays;
  for (int i = 0; i < 8; ++i) delays.push_back(backoff.next().count());
  EXPECT_EQ(delays, (std::vector<long>{200, 400, 800, 1600, 3200, 5000, 5000, 5000}));
  EXPECT_EQ(backoff.retries(), 8);
  backoff.reset();
  EXPECT_EQ(backoff.next().count(), 200);
  EXPECT_EQ(backoff.nominal(100).count(), 5000);  // no overflow far out
}

TEST(ClientBackoff, JitterStaysInItsWindowAndVaries) {
  client::Backoff backoff(
      {std::chrono::milliseconds(1000), 1.0, std::chrono::milliseconds(5000), 0.25}, 42);
  std::set<long> seen;
  for (int i = 0; i < 200; ++i) {
    const long d = backoff.next().count();
    EXPECT_GE(d, 750);
    EXPECT_LE(d, 1250);
    seen.insert(d);
  }
  EXPECT_GT(seen.size(), 50u);  // spread, not lockstep
}

// ---------------------------------------------------------------------------------------------
// Reassembly

v1::LabelChunk chunk(std::uint64_t first, std::uint32_t count, int descriptor_dim = 0) {
  v1::LabelChunk c;
  c.set_first_point(first);
  c.set_point_count(count);
  std::vector<std::uint32_t> labels(count);
  for (std::uint32_t i = 0; i < count; ++i) labels[i] = static_cast<std::uint32_t>(first + i);
  c.set_labels(wire::pack_u32(labels.data(), count));
  if (descriptor_dim > 0) {
    std::vector<float> d(count * descriptor_dim, 1.0f);
    c.set_descriptors(wire::pack_f32(d.data(), d.size()));
  }
  return c;
}

v1::LabelSummary summary_for(std::uint64_t points) {
  v1::LabelSummary s;
  s.set_points_received(points);
  return s;
}

TEST(ClientAssembler, AcceptsChunksInAnyOrderAndKeysThemToInputOrder) {
  client::LabelAssembler assembler(10, false, false);
  assembler.add(chunk(6, 4));
  assembler.add(chunk(0, 3));
  assembler.add(chunk(3, 3));
  const auto result = assembler.finish(summary_for(10));
  for (std::uint32_t i = 0; i < 10; ++i) EXPECT_EQ(result.labels[i], i);
}

TEST(ClientAssembler, RejectsGapsOverlapsAndRunsPastTheEnd) {
  {
    client::LabelAssembler assembler(10, false, false);
    assembler.add(chunk(0, 4));
    assembler.add(chunk(5, 5));
    try {
      assembler.finish(summary_for(10));
      FAIL() << "a gap was accepted";
    } catch (const client::ProtocolError& e) {
      EXPECT_NE(std::string(e.what()).find("first missing point 4"), std::string::npos);
    }
  }
  {
    client::LabelAssembler assembler(10, false, false);
    assembler.add(chunk(0, 5));
    EXPECT_THROW(assembler.add(chunk(4, 6)), client::ProtocolError);
  }
  {
    client::LabelAssembler assembler(10, false, false);
    EXPECT_THROW(assembler.add(chunk(8, 3)), client::ProtocolError);
    EXPECT_THROW(assembler.add(chunk(~0ull, 2)), client::ProtocolError);  // no wrap-around
  }
}

TEST(ClientAssembler, RejectsMismatchedArraySizes) {
  client::LabelAssembler assembler(4, true, false);
  v1::LabelChunk bad = chunk(0, 2, 33);
  bad.mutable_labels()->pop_back();
  EXPECT_THROW(assembler.add(bad), client::ProtocolError);
  assembler.add(chunk(0, 2, 33));
  EXPECT_THROW(assembler.add(chunk(2, 2, 32)), client::ProtocolError);  // width changed
  EXPECT_THROW(assembler.add(chunk(2, 2)), client::ProtocolError);      // asked for, missing
  assembler.add(chunk(2, 2, 33));
  v1::LabelSummary s = summary_for(4);
  s.set_descriptor_dim(125);
  EXPECT_THROW(assembler.finish(s), client::ProtocolError);
}

TEST(ClientAssembler, RejectsASummaryThatCountedOtherPoints) {
  client::LabelAssembler assembler(3, false, false);
  assembler.add(chunk(0, 3));
  EXPECT_THROW(assembler.finish(summary_for(4)), client::ProtocolError);
}

// Object ids: one a point, asked for means present, and each names the table or an object of
// the summary.
TEST(ClientAssembler, ChecksObjectIdsAgainstTheSummary) {
  const auto with_objects = [](std::uint64_t first, std::vector<std::uint32_t> ids) {
    v1::LabelChunk c = chunk(first, std::uint32_t(ids.size()));
    c.set_objects(wire::pack_u32(ids.data(), ids.size()));
    return c;
  };
  v1::LabelSummary s = summary_for(4);
  s.mutable_table();
  s.add_objects()->set_object_id(1);
  {
    client::LabelAssembler assembler(4, false, false, false, true);
    assembler.add(with_objects(0, {0, 1}));
    EXPECT_THROW(assembler.add(chunk(2, 2)), client::ProtocolError);  // asked for, missing
    assembler.add(with_objects(2, {0xFFFFFFFFu, 1}));
    const auto result = assembler.finish(s);
    EXPECT_EQ(result.object_ids, (std::vector<std::uint32_t>{0, 1, 0xFFFFFFFFu, 1}));
    EXPECT_EQ(result.objects().size(), 1);
    EXPECT_TRUE(result.has_table());
  }
  {
    client::LabelAssembler assembler(4, false, false, false, true);
    assembler.add(with_objects(0, {0, 1, 2, 1}));  // object 2 is not in the summary
    EXPECT_THROW(assembler.finish(s), client::ProtocolError);
  }
  {
    client::LabelAssembler assembler(2, false, false, false, true);
    assembler.add(with_objects(0, {0, 1}));  // the table, but the summary has none
    v1::LabelSummary no_table = summary_for(2);
    no_table.add_objects()->set_object_id(1);
    EXPECT_THROW(assembler.finish(no_table), client::ProtocolError);
  }
}

// ---------------------------------------------------------------------------------------------
// Calls against the fake server

TEST(ClientCalls, ObjectsComeWithTheirPerPointIds) {
  FakeServer server;
  Client client(fast_options(server.address()));
  for (const bool unary : {false, true}) {
    const LabelOptions options = label_options([](auto& o) {
      o.tabletop_only = true;
      o.objects = true;
      o.response_chunk_points = 256;
    });
    const auto result = unary ? client.label_unary(labeled_line(1000), options)
                              : client.label(labeled_line(1000), options);
    ASSERT_EQ(result.object_ids.size(), 1000u);
    for (std::size_t i = 0; i < 1000; ++i) {  // label i % 7: 1 table, 2 and 3 objects
      const std::uint32_t label = std::uint32_t(i % 7);
      const std::uint32_t want = label == 1 ? 0u : label == 2 ? 1u : label == 3 ? 2u : 0xFFFFFFFFu;
      ASSERT_EQ(result.object_ids[i], want) << i;
    }
    ASSERT_TRUE(result.has_table());
    EXPECT_DOUBLE_EQ(result.table().offset(), -0.3);
    ASSERT_EQ(result.objects().size(), 2);
    EXPECT_EQ(result.objects().Get(1).object_id(), 2u);
    EXPECT_DOUBLE_EQ(result.objects().Get(1).height(), 0.2);
  }
  // Without tabletop_only the (fake) server refuses, as the real one does.
  const LabelOptions refused = label_options([](auto& o) { o.objects = true; });
  try {
    client.label(labeled_line(10), refused);
    FAIL() << "objects without tabletop_only were accepted";
  } catch (const ClientError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::INVALID_ARGUMENT);
  }
}

TEST(ClientCalls, StreamsInChunksAndReassemblesLabelsDescriptorsProbabilities) {
  FakeServer server;
  Client client(fast_options(server.address()));
  const PointCloud cloud = labeled_line(2500);
  LabelOptions options;
  options.chunk_points = 300;
  options.response_chunk_points = 700;
  options.descriptors = true;
  options.probabilities = true;
  options.scan_id = "scan-1";
  std::vector<std::size_t> progress;
  const auto result = client.label(
      cloud, options, [&](std::size_t sent, std::size_t) { progress.push_back(sent); });
  ASSERT_EQ(result.size(), 2500u);
  for (std::size_t i = 0; i < cloud.size(); ++i) ASSERT_EQ(result.labels[i], i % 7) << i;
  EXPECT_EQ(server.service.chunks_received, 9);  // ceil(2500 / 300)
  EXPECT_EQ(progress.size(), 9u);
  EXPECT_EQ(progress.back(), 2500u);
  ASSERT_EQ(result.descriptor_dim, 33);
  EXPECT_FLOAT_EQ(result.descriptors[1234 * 33 + 5], 1234.05f);
  ASSERT_EQ(result.class_ids.size(), 3u);
  ASSERT_EQ(result.probabilities.size(), 2500u * 3);
  EXPECT_EQ(result.probabilities[10 * 3 + (10 % 7) % 3], 1.0f);
  EXPECT_EQ(result.summary.scan_id(), "scan-1");
  EXPECT_EQ(result.attempts, 1);
}

// LabelResult::client_seconds: every stage of a streamed call is timed, the wait for the
// answer in `receive`; a unary call has no separate send.
TEST(ClientCalls, TheClientsOwnStagesAreTimed) {
  FakeServer server;
  Client client(fast_options(server.address()));
  const auto streamed = client.label(labeled_line(2000));
  EXPECT_GT(streamed.client_seconds.encode, 0.0);
  EXPECT_GT(streamed.client_seconds.send, 0.0);
  EXPECT_GT(streamed.client_seconds.receive, 0.0);
  EXPECT_GT(streamed.client_seconds.decode, 0.0);
  const auto unary = client.label_unary(labeled_line(2000));
  EXPECT_GT(unary.client_seconds.encode, 0.0);
  EXPECT_EQ(unary.client_seconds.send, 0.0);
  EXPECT_GT(unary.client_seconds.receive, 0.0);
  EXPECT_GT(unary.client_seconds.decode, 0.0);
}

TEST(ClientCalls, ChunksAnsweredInReverseOrderStillLandInInputOrder) {
  FakeServer server;
  server.service.reversed_chunks = true;
  Client client(fast_options(server.address()));
  const auto result = client.label(labeled_line(3000),
                                   label_options([](auto& o) { o.response_chunk_points = 256; }));
  for (std::size_t i = 0; i < 3000; ++i) ASSERT_EQ(result.labels[i], i % 7);
}

// LabelOptions::every_point reaches the header, streamed and unary; off by default (the
// server's plane cascade).
TEST(ClientCalls, EveryPointReachesTheRequest) {
  FakeServer server;
  Client client(fast_options(server.address()));
  client.label(labeled_line(50), LabelOptions{});
  client.label(labeled_line(50), label_options([](auto& o) { o.every_point = true; }));
  client.label_unary(labeled_line(50), label_options([](auto& o) { o.every_point = true; }));
  std::lock_guard lock(server.service.mutex);
  ASSERT_EQ(server.service.options.size(), 3u);
  EXPECT_FALSE(server.service.options[0].every_point());
  EXPECT_TRUE(server.service.options[1].every_point());
  EXPECT_TRUE(server.service.options[2].every_point());
}

TEST(ClientCalls, UnaryLabelsInOneMessage) {
  FakeServer server;
  Client client(fast_options(server.address()));
  const auto result =
      client.label_unary(labeled_line(100), label_options([](auto& o) { o.descriptors = true; }));
  ASSERT_EQ(result.size(), 100u);
  EXPECT_EQ(result.labels[13], 13u % 7);
  EXPECT_EQ(result.descriptor_dim, 33);
}

TEST(ClientCalls, RetriesUnavailableWithBackoffThenSucceeds) {
  FakeServer server;
  server.service.unavailable_calls = 2;
  Client client(fast_options(server.address()));
  const auto result = client.label(labeled_line(10));
  EXPECT_EQ(result.attempts, 3);
  EXPECT_EQ(server.service.label_calls, 3);
}

TEST(ClientCalls, GivesUpAfterTheBoundedAttempts) {
  FakeServer server;
  server.service.unavailable_calls = 100;
  ClientOptions options = fast_options(server.address());
  options.retry_attempts = 3;
  Client client(options);
  try {
    client.label(labeled_line(10));
    FAIL() << "no error";
  } catch (const ClientError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::UNAVAILABLE);
    EXPECT_EQ(e.attempts(), 3);
  }
  EXPECT_EQ(server.service.label_calls, 3);
}

TEST(ClientCalls, DoesNotRetryARejection) {
  FakeServer server;
  Client client(fast_options(server.address()));
  try {
    client.label(labeled_line(10), label_options([](auto& o) { o.model = "nope"; }));
    FAIL() << "no error";
  } catch (const ClientError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::NOT_FOUND);
    EXPECT_EQ(e.attempts(), 1);
    EXPECT_NE(std::string(e.what()).find("NOT_FOUND: no model 'nope'"), std::string::npos);
  }
}

TEST(ClientCalls, AnAnswerMissingOrRepeatingAPointIsDataLoss) {
  FakeServer server;
  Client client(fast_options(server.address()));
  server.service.skip_a_point = true;
  try {
    client.label(labeled_line(2000));
    FAIL() << "no error";
  } catch (const ClientError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::DATA_LOSS);
    EXPECT_NE(std::string(e.what()).find("1999 of 2000"), std::string::npos) << e.what();
  }
  server.service.skip_a_point = false;
  server.service.repeat_a_point = true;
  try {
    client.label(labeled_line(2000));
    FAIL() << "no error";
  } catch (const ClientError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::DATA_LOSS);
    EXPECT_NE(std::string(e.what()).find("twice"), std::string::npos) << e.what();
  }
}

TEST(ClientCalls, SendsTheBearerToken) {
  FakeServer server;
  server.service.required_token = "s3cret";
  {
    Client client(fast_options(server.address()));
    try {
      client.label(labeled_line(5));
      FAIL() << "no error";
    } catch (const ClientError& e) {
      EXPECT_EQ(e.code(), grpc::StatusCode::UNAUTHENTICATED);
    }
  }
  ClientOptions options = fast_options(server.address());
  options.bearer_token = "s3cret";
  Client client(options);
  EXPECT_EQ(client.label(labeled_line(5)).size(), 5u);
}

TEST(ClientCalls, AsyncLabelCallsBackWithTheResult) {
  FakeServer server;
  Client client(fast_options(server.address()));
  std::promise<std::pair<client::CallStatus, client::LabelResult>> outcome;
  auto handle = client.label_async(labeled_line(500), {}, [&](auto status, auto result) {
    outcome.set_value({std::move(status), std::move(result)});
  });
  auto [status, result] = outcome.get_future().get();
  handle.wait();
  EXPECT_TRUE(handle.done());
  EXPECT_TRUE(status.ok()) << status.message;
  ASSERT_EQ(result.size(), 500u);
  EXPECT_EQ(result.labels[499], 499u % 7);
}

TEST(ClientCalls, ManyAsyncCallsAtOnce) {
  FakeServer server;
  Client client(fast_options(server.address()));
  std::atomic<int> ok{0};
  std::vector<client::CallHandle> handles;
  for (int i = 0; i < 16; ++i)
    handles.push_back(client.label_async(
        labeled_line(100 + i), {},
        [&, i](client::CallStatus status, auto result) {
          if (status.ok() && result.size() == 100u + i) ++ok;
        },
        /*unary=*/i % 2 == 0));
  for (auto& h : handles) h.wait();
  EXPECT_EQ(ok, 16);
}

TEST(ClientCalls, AsyncCallCanBeCancelled) {
  FakeServer server;
  server.service.delay_ms = 20'000;
  Client client(fast_options(server.address()));
  std::promise<client::CallStatus> outcome;
  auto handle = client.label_async(labeled_line(10), {},
                                   [&](auto status, auto) { outcome.set_value(status); });
  handle.cancel();
  const auto status = outcome.get_future().get();
  EXPECT_EQ(status.code, grpc::StatusCode::CANCELLED);
}

TEST(ClientCalls, ListsModelsReadsMetadataAndHealth) {
  FakeServer server;
  Client client(fast_options(server.address()));
  const auto models = client.list_models();
  ASSERT_EQ(models.size(), 1u);
  EXPECT_EQ(models[0].name(), "fake");
  EXPECT_EQ(client.model_metadata("fake").classes_size(), 3);
  EXPECT_EQ(client.health(), client::HealthStatus::kServing);
  server.set_serving(false);
  EXPECT_EQ(client.health(), client::HealthStatus::kNotServing);
}

TEST(ClientCalls, AnUnreachableServerIsUnavailableAfterRetries) {
  // A port that was just free: bind 127.0.0.1:0 through a server and shut it down.
  std::string address;
  { address = FakeServer().address(); }
  ClientOptions options = fast_options(address);
  options.retry_attempts = 2;
  Client client(options);
  try {
    client.health();
    FAIL() << "no error";
  } catch (const ClientError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::UNAVAILABLE);
    EXPECT_EQ(e.attempts(), 2);
  }
}

TEST(ClientCalls, DeadlineBoundsASlowCall) {
  FakeServer server;
  server.service.delay_ms = 20'000;
  ClientOptions options = fast_options(server.address());
  options.deadline = std::chrono::milliseconds(300);
  Client client(options);
  try {
    client.label(labeled_line(10));
    FAIL() << "no error";
  } catch (const ClientError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  }
}

TEST(ClientCalls, UnreadableTlsFilesAreAnError) {
  ClientOptions options;
  options.tls.emplace();
  options.tls->ca_file = "/nonexistent/ca.pem";
  try {
    Client client(options);
    FAIL() << "no error";
  } catch (const ClientError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/ca.pem"), std::string::npos);
  }
}

}  // namespace
}  // namespace primlabel
