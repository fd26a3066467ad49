// The stream limits without a transport (service/stream_limits.hpp): the order of a Label call's
// messages, the idle limit while the scan comes in, the receive rate after its grace window, and
// the time an answer message may wait to be taken; the clock is the test's own.

#include <gtest/gtest.h>

#include <chrono>

#include "primlabel/service/stream_limits.hpp"

namespace primlabel::service {
namespace {

using Clock = StreamLimits::Clock;
using std::chrono::milliseconds;

ops::ServerConfig limits_config() {
  ops::ServerConfig config;
  config.stream_idle_seconds = 2;
  config.min_receive_bytes_per_second = 1000;
  config.receive_rate_window_seconds = 1;
  config.send_timeout_seconds = 3;
  return config;
}

v1::LabelRequest header_message() {
  v1::LabelRequest request;
  request.mutable_header();
  return request;
}

v1::LabelRequest chunk_message() {
  v1::LabelRequest request;
  request.mutable_chunk();
  return request;
}

TEST(StreamLimits, AHeaderFirstThenChunksOrTheEnd) {
  EXPECT_FALSE(out_of_order(StreamPhase::kHeader, header_message(), 1));
  const auto chunk_first = out_of_order(StreamPhase::kHeader, chunk_message(), 1);
  ASSERT_TRUE(chunk_first);
  EXPECT_EQ(chunk_first->code, ErrorCode::kInvalidArgument);
  EXPECT_NE(chunk_first->message.find("must be a ScanHeader, got a PointChunk"), std::string::npos);

  EXPECT_FALSE(out_of_order(StreamPhase::kReceiving, chunk_message(), 2));
  v1::LabelRequest end;
  end.mutable_end();
  EXPECT_FALSE(out_of_order(StreamPhase::kReceiving, end, 3));
  const auto second_header = out_of_order(StreamPhase::kReceiving, header_message(), 4);
  ASSERT_TRUE(second_header);
  EXPECT_NE(second_header->message.find("message 4 is a ScanHeader"), std::string::npos);
  EXPECT_TRUE(out_of_order(StreamPhase::kReceiving, v1::LabelRequest{}, 5));
}

TEST(StreamLimits, AStreamWithoutMessagesForTheIdleTimeEnds) {
  const ops::ServerConfig config = limits_config();
  const Clock::time_point t0{};
  StreamLimits limits(config, t0);
  EXPECT_EQ(limits.next_check(StreamPhase::kHeader), t0 + std::chrono::seconds(2));
  EXPECT_FALSE(limits.check(StreamPhase::kHeader, t0 + milliseconds(1999)));
  const auto idle = limits.check(StreamPhase::kHeader, t0 + std::chrono::seconds(2));
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->code, ErrorCode::kDeadlineExceeded);
  EXPECT_NE(idle->message.find("waiting for the ScanHeader (--stream-idle-seconds)"),
            std::string::npos);
  // While labeling nothing comes in, and nothing is due.
  EXPECT_FALSE(limits.check(StreamPhase::kLabeling, t0 + std::chrono::seconds(60)));
  EXPECT_EQ(limits.next_check(StreamPhase::kLabeling), Clock::time_point::max());
}

TEST(StreamLimits, TheRateIsJudgedAfterAGraceWindowThenPerWindow) {
  const ops::ServerConfig config = limits_config();
  const Clock::time_point t0{};
  StreamLimits limits(config, t0);
  limits.message_arrived(100, t0);
  limits.receiving_started(t0);
  // The first check comes two windows after the header.
  EXPECT_EQ(limits.next_check(StreamPhase::kReceiving), t0 + std::chrono::seconds(2));
  limits.message_arrived(1500, t0 + milliseconds(500));
  limits.message_arrived(1500, t0 + milliseconds(1500));
  EXPECT_FALSE(limits.check(StreamPhase::kReceiving, t0 + std::chrono::seconds(2)));  // 1500 B/s
  // The next window starts there: 500 bytes in the following second is too slow.
  EXPECT_EQ(limits.next_check(StreamPhase::kReceiving), t0 + std::chrono::seconds(3));
  limits.message_arrived(500, t0 + milliseconds(2500));
  const auto slow = limits.check(StreamPhase::kReceiving, t0 + std::chrono::seconds(3));
  ASSERT_TRUE(slow);
  EXPECT_EQ(slow->code, ErrorCode::kResourceExhausted);
  EXPECT_NE(slow->message.find("--min-receive-bytes-per-second"), std::string::npos);
}

TEST(StreamLimits, AnAnswerMessageNotTakenInTimeEndsTheCall) {
  const ops::ServerConfig config = limits_config();
  const Clock::time_point t0{};
  StreamLimits limits(config, t0);
  EXPECT_EQ(limits.next_check(StreamPhase::kSending), Clock::time_point::max());
  limits.write_started(t0 + std::chrono::seconds(10));
  EXPECT_TRUE(limits.write_pending());
  EXPECT_EQ(limits.next_check(StreamPhase::kSending), t0 + std::chrono::seconds(13));
  EXPECT_FALSE(limits.check(StreamPhase::kSending, t0 + std::chrono::seconds(12)));
  const auto stalled = limits.check(StreamPhase::kSending, t0 + std::chrono::seconds(13));
  ASSERT_TRUE(stalled);
  EXPECT_NE(stalled->message.find("--send-timeout-seconds"), std::string::npos);
  limits.write_done();
  EXPECT_FALSE(limits.check(StreamPhase::kSending, t0 + std::chrono::seconds(30)));
}

}  // namespace
}  // namespace primlabel::service
