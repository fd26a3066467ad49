#pragma once
// A fixed number of places (e.g. streams receiving points): take one or be refused at once.

#include <atomic>
#include <optional>
#include <utility>

namespace primlabel::service {

class SlotBudget {
 public:
  explicit SlotBudget(int capacity) : capacity_(capacity) {}
  SlotBudget(const SlotBudget&) = delete;
  SlotBudget& operator=(const SlotBudget&) = delete;

  // One place, given back when destroyed.
  class Slot {
   public:
    Slot(Slot&& other) noexcept : budget_(std::exchange(other.budget_, nullptr)) {}
    Slot& operator=(Slot&& other) noexcept {
      if (this != &other) {
        release();
        budget_ = std::exchange(other.budget_, nullptr);
      }
      return *this;
    }
    ~Slot() { release(); }

   private:
    friend class SlotBudget;
    explicit Slot(SlotBudget* budget) : budget_(budget) {}
    void release() {
      if (budget_) std::exchange(budget_, nullptr)->used_.fetch_sub(1);
    }
    SlotBudget* budget_;
  };

  std::optional<Slot> try_take() {
    int used = used_.load();
    do {
      if (used >= capacity_) return std::nullopt;
    } while (!used_.compare_exchange_weak(used, used + 1));
    return Slot(this);
  }

  int used() const { return used_.load(); }
  int capacity() const { return capacity_; }

 private:
  const int capacity_;
  std::atomic<int> used_{0};
};

}  // namespace primlabel::service
