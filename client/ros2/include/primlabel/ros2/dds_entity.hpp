#pragma once
// Cyclone DDS's C API held RAII-style: an entity (participant, topic, reader, writer, waitset,
// condition) deleted with its owner, and a sample loaned by dds_take returned with its guard.

#include <dds/dds.h>

#include <stdexcept>
#include <string>
#include <utility>

namespace primlabel::ros2node {

// `result` when it is an entity or a success, else std::runtime_error naming `what` and DDS's
// reason.
inline dds_entity_t checked(dds_entity_t result, const std::string& what) {
  if (result < 0) throw std::runtime_error(what + ": " + dds_strretcode(result));
  return result;
}

class DdsEntity {
 public:
  DdsEntity() = default;
  explicit DdsEntity(dds_entity_t entity) : entity_(entity) {}
  DdsEntity(DdsEntity&& other) noexcept : entity_(std::exchange(other.entity_, 0)) {}
  DdsEntity& operator=(DdsEntity&& other) noexcept {
    if (this != &other) reset(std::exchange(other.entity_, 0));
    return *this;
  }
  DdsEntity(const DdsEntity&) = delete;
  DdsEntity& operator=(const DdsEntity&) = delete;
  ~DdsEntity() { reset(0); }

  dds_entity_t get() const { return entity_; }

 private:
  // Deleting a participant deletes its children too; deleting one of those afterwards only
  // returns an error, which is ignored.
  void reset(dds_entity_t entity) {
    if (entity_ > 0) dds_delete(entity_);
    entity_ = entity;
  }
  dds_entity_t entity_ = 0;
};

// One sample taken on loan (dds_take with a null buffer), returned to the reader on destruction.
class LoanedSample {
 public:
  LoanedSample(dds_entity_t reader, void* sample) : reader_(reader), sample_(sample) {}
  LoanedSample(const LoanedSample&) = delete;
  LoanedSample& operator=(const LoanedSample&) = delete;
  ~LoanedSample() {
    if (sample_) dds_return_loan(reader_, &sample_, 1);
  }
  template <class T>
  const T& as() const {
    return *static_cast<const T*>(sample_);
  }

 private:
  dds_entity_t reader_;
  void* sample_;
};

}  // namespace primlabel::ros2node
