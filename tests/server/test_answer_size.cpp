// The answer's bytes per point have one definition (service/answer_size.hpp): the chunks the
// responder cuts carry exactly that many bytes of packed arrays per point, and as many points as
// that size fits in the byte budget.

#include <gtest/gtest.h>

#include "primlabel/service/answer_size.hpp"
#include "primlabel/service/label_response.hpp"

namespace primlabel::service {
namespace {

pipeline::LabelingResult every_array(std::size_t points, int dim, int classes) {
  pipeline::LabelingResult result;
  result.labels.assign(points, 1);
  result.descriptors = Descriptors(dim, std::vector<float>(points * std::size_t(dim), 0.5f));
  result.probabilities = Eigen::MatrixXf::Constant(Eigen::Index(points), classes, 0.25f);
  result.primitives.emplace();
  result.primitives->point_segment.assign(points, 0);
  result.objects.emplace();
  result.objects->point_object.assign(points, 0);
  return result;
}

std::uint64_t packed_bytes(const v1::LabelChunk& chunk) {
  return chunk.labels().size() + chunk.descriptors().size() + chunk.probabilities().size() +
         chunk.segments().size() + chunk.objects().size();
}

TEST(AnswerSize, AChunkCarriesTheArraysPerPointAndAsManyPointsAsFit) {
  const pipeline::LabelingResult result = every_array(10, 33, 5);
  const std::uint64_t per_point = array_bytes_per_point({33, 5, true, true});
  EXPECT_EQ(per_point, 4u + 4u * 33 + 4u * 5 + 4u + 4u);
  const LabelResponder whole(result, 0, 1 << 20);
  v1::LabelChunk chunk;
  whole.fill_chunk(0, chunk);
  EXPECT_EQ(packed_bytes(chunk), 10 * per_point);
  const LabelResponder three(result, 0, 3 * per_point + per_point - 1);
  EXPECT_EQ(three.chunk_points(), 3u);
  EXPECT_EQ(three.chunk_count(), 4u);

  pipeline::LabelingResult labels_only;
  labels_only.labels.assign(10, 1);
  const LabelResponder plain(labels_only, 0, 1 << 20);
  v1::LabelChunk small;
  plain.fill_chunk(0, small);
  EXPECT_EQ(packed_bytes(small), 10 * array_bytes_per_point({}));
}

}  // namespace
}  // namespace primlabel::service
