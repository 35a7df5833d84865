#pragma once
// The visible part of a line sample: a sorted list of disjoint sub-intervals of the segment's
// parameter t in [0,1] (Billen & Dutré 2016 Sec. 5.2: "we start with a fully visible line
// sample; every back-projected intersection clips a part from the still visible intervals").
//
// Cuts are closed intervals and the visible pieces are the closures of the open components of
// [0,1] minus the union of all cuts. Two cuts that touch ([t0,t1] and [t1,t2]) leave nothing
// visible between them, so a closed mesh whose cuts share endpoints bit for bit never leaks.
// The result does not depend on the order in which cuts are subtracted.
//
// Storage: up to kInlineCapacity pieces inline (no allocation in the common case), then the
// heap. Double precision: the endpoints are copied from exact leaf computations, never
// recomputed, so pieces that should touch do.

#include <algorithm>
#include <cstddef>
#include <memory>

namespace penumbra {

struct Interval {
  double lo = 0, hi = 0;
  double length() const { return hi - lo; }
};

class IntervalList {
 public:
  static constexpr size_t kInlineCapacity = 8;

  // A new list holds the whole segment [0,1], visible.
  IntervalList() { reset(); }
  IntervalList(const IntervalList& other) { assign(other); }
  IntervalList& operator=(const IntervalList& other) {
    if (this != &other) assign(other);
    return *this;
  }
  IntervalList(IntervalList&& other) noexcept { assign(other); }
  IntervalList& operator=(IntervalList&& other) noexcept {
    if (this != &other) assign(other);
    return *this;
  }

  // One visible piece [lo, hi] (nothing visible when lo >= hi).
  void reset(double lo = 0, double hi = 1) {
    size_ = 0;
    if (lo < hi) pieces_[size_++] = {lo, hi};
  }
  // Nothing visible.
  void clear() { size_ = 0; }

  // Removes the closed interval [lo, hi]. Empty or NaN cuts (not lo < hi) change nothing.
  void subtract(double lo, double hi) {
    if (!(lo < hi)) return;
    // First piece that ends after the cut starts (a piece ending exactly at lo is untouched).
    const size_t first = first_ending_after(lo);
    if (first == size_ || !(pieces_[first].lo < hi)) return;
    // One past the last piece that starts before the cut ends.
    size_t last = first + 1;
    while (last < size_ && pieces_[last].lo < hi) ++last;

    // What stays of the first and the last piece touched: [first.lo, lo] and [hi, last.hi].
    const bool keep_left = pieces_[first].lo < lo;
    const bool keep_right = hi < pieces_[last - 1].hi;
    const size_t removed = last - first;
    if (removed == 1 && keep_left != keep_right) {
      // The cut covers one end of one piece (the common case): trim it in place.
      if (keep_left) {
        pieces_[first].hi = lo;
      } else {
        pieces_[first].lo = hi;
      }
      return;
    }
    const size_t kept = size_t(keep_left) + size_t(keep_right);
    const Interval left{pieces_[first].lo, lo}, right{hi, pieces_[last - 1].hi};
    const size_t new_size = size_ - removed + kept;
    if (new_size > capacity_) grow(new_size);
    // Shift the tail (a few pieces: plain loops, no call), then write what stays.
    if (kept > removed) {
      for (size_t i = size_; i-- > last;) pieces_[i + kept - removed] = pieces_[i];
    } else if (kept < removed) {
      for (size_t i = last; i < size_; ++i) pieces_[i - (removed - kept)] = pieces_[i];
    }
    size_t at = first;
    if (keep_left) pieces_[at++] = left;
    if (keep_right) pieces_[at] = right;
    size_ = new_size;
  }

  // Would subtracting [lo, hi] change the list? (Some piece overlaps the open interval.)
  bool overlaps(double lo, double hi) const {
    size_t first = first_ending_after(lo);
    return first < size_ && pieces_[first].lo < hi;
  }

  bool fully_occluded() const { return size_ == 0; }
  double visible_length() const {
    double total = 0;
    for (size_t i = 0; i < size_; ++i) total += pieces_[i].length();
    return total;
  }
  // Smallest and largest visible t (only when not fully occluded).
  double lowest() const { return pieces_[0].lo; }
  double highest() const { return pieces_[size_ - 1].hi; }

  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const Interval& operator[](size_t i) const { return pieces_[i]; }
  const Interval* begin() const { return pieces_; }
  const Interval* end() const { return pieces_ + size_; }

 private:
  // Index of the first piece with hi > t (size_ when none): a linear scan for the few pieces
  // of the common case, a binary search past that.
  size_t first_ending_after(double t) const {
    if (size_ <= 8) {
      size_t i = 0;
      while (i < size_ && pieces_[i].hi <= t) ++i;
      return i;
    }
    size_t lo = 0, hi = size_;
    while (lo < hi) {
      size_t mid = (lo + hi) / 2;
      if (pieces_[mid].hi <= t) {
        lo = mid + 1;
      } else {
        hi = mid;
      }
    }
    return lo;
  }

  void grow(size_t needed) {
    size_t new_capacity = std::max(needed, 2 * capacity_);
    std::unique_ptr<Interval[]> storage(new Interval[new_capacity]);
    std::copy(pieces_, pieces_ + size_, storage.get());
    heap_ = std::move(storage);
    pieces_ = heap_.get();
    capacity_ = new_capacity;
  }

  void assign(const IntervalList& other) {
    size_ = 0;
    if (other.size_ > capacity_) grow(other.size_);
    std::copy(other.begin(), other.end(), pieces_);
    size_ = other.size_;
  }

  Interval inline_[kInlineCapacity];
  std::unique_ptr<Interval[]> heap_;
  Interval* pieces_ = inline_;  // inline_ or heap_: the pieces, sorted
  size_t size_ = 0;
  size_t capacity_ = kInlineCapacity;
};

}  // namespace penumbra
