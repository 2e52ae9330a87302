// SPDX-License-Identifier: Apache-2.0
// FrameOutput: where a revolution-cutting frame assembler (Hesai, Velodyne) writes points.
//
// A point belongs to the revolution its own azimuth falls in, so near the cut two frames are
// open at once: the frame in progress, whose points go to the caller's span (a SIM writer's
// loaned slot), and the next one, whose first points wait in a carry-over buffer. When the
// frame in progress is handed out, the span is the caller's until it gives the next one
// (attach); until then the carry-over holds the new frame in progress, and attach() moves it
// to the front of the new span. Nothing is allocated after reserve_carry().
//
// Replacing the span while a frame is in progress (attach() while attached) keeps the
// carry-over where it is: it holds the *next* frame's points, which must not become the front
// of the frame in progress. The points already in the old span are lost to the frame in
// progress (attach() says how many: the frame is then not whole). (Velodyne's assembler used to
// copy the carry-over to the new span here, putting the next revolution's points into this one
// and losing them from the next.)
//
// Header-only and on the core alone: the family decoders include it, and the per-point calls
// are inline. The assembler keeps its frames' state (stamps, counts, whole) and counters; this
// class only says how many points it could not keep.
#pragma once

#include <algorithm>
#include <cstddef>
#include <span>
#include <vector>

#include "sim/lidar_point.hpp"

namespace sim::lidar {

class FrameOutput {
 public:
  // One frame's storage and fill, for a loop that writes many points before storing the count.
  struct Storage {
    LidarPoint* data = nullptr;
    std::size_t capacity = 0;
    std::size_t count = 0;
  };
  // What attach() cost the frame in progress.
  struct Attached {
    std::size_t lost = 0;         // points in the span it replaced (the frame is not whole)
    std::size_t did_not_fit = 0;  // carry-over points the new span had no room for
  };
  // What advance() threw away.
  struct Advanced {
    std::size_t discarded = 0;    // the frame in progress's points (no span: they were carried)
    std::size_t did_not_fit = 0;  // carry-over points the span had no room for
  };

  // Sizes the carry-over (at the assembler's create(): the only allocation).
  void reserve_carry(std::size_t points) { carry_.assign(points, LidarPoint{}); }
  std::size_t carry_capacity() const noexcept { return carry_.size(); }

  // The span the frame in progress goes to. Without a span, the carry-over held the frame in
  // progress: it moves to the span's front. With one (replaced mid-frame), see the top.
  Attached attach(std::span<LidarPoint> output) noexcept {
    Attached result;
    if (attached_) {
      result.lost = output_count_;
      output_ = output;
      output_count_ = 0;
      return result;
    }
    output_ = output;
    attached_ = true;
    const std::size_t moved = std::min(carry_count_, output_.size());
    std::copy_n(carry_.begin(), moved, output_.begin());
    result.did_not_fit = carry_count_ - moved;
    output_count_ = moved;
    carry_count_ = 0;
    return result;
  }

  // The frame in progress was handed out: its `output_count()` points at the front of the span
  // are the caller's, and the span with them. The carry-over holds the new frame in progress.
  void hand_out() noexcept {
    output_ = {};
    attached_ = false;
    output_count_ = 0;
  }

  // The frame in progress ends without being handed out (a partial frame dropped, no span to
  // put it in): its points are thrown away and the next frame takes over its storage, the
  // carry-over moving to the span's front when there is one.
  Advanced advance() noexcept {
    Advanced result;
    if (!attached_) {
      result.discarded = carry_count_;  // the frame in progress; the next one had no storage
      carry_count_ = 0;
      return result;
    }
    result.discarded = output_count_;
    const std::size_t moved = std::min(carry_count_, output_.size());
    std::copy_n(carry_.begin(), moved, output_.begin());
    result.did_not_fit = carry_count_ - moved;
    output_count_ = moved;
    carry_count_ = 0;
    return result;
  }

  // Forgets the next frame's points (the frame in progress is finished early); returns how
  // many. Without a span the carry-over is the frame in progress's and stays.
  std::size_t drop_next() noexcept {
    if (!attached_) return 0;
    const std::size_t dropped = carry_count_;
    carry_count_ = 0;
    return dropped;
  }

  // Forgets every point of both frames (a reset, a gap); the span, if any, stays attached.
  void clear() noexcept {
    output_count_ = 0;
    carry_count_ = 0;
  }

  // Moves the last `n` points of the span to the end of the carry-over (a frame that ends
  // inside a packet: the packet's trailing points belong to the next frame); returns them there,
  // or nothing (and moves nothing) when there is no span, fewer points, or no room.
  std::span<LidarPoint> move_tail_to_carry(std::size_t n) noexcept {
    if (n == 0 || !attached_ || output_count_ < n || carry_.size() - carry_count_ < n) return {};
    std::copy_n(output_.begin() + static_cast<std::ptrdiff_t>(output_count_ - n), n,
                carry_.begin() + static_cast<std::ptrdiff_t>(carry_count_));
    output_count_ -= n;
    const std::span<LidarPoint> moved(carry_.data() + carry_count_, n);
    carry_count_ += n;
    return moved;
  }

  bool attached() const noexcept { return attached_; }
  // Points the frame in progress holds.
  std::size_t pending() const noexcept { return attached_ ? output_count_ : carry_count_; }
  std::size_t output_count() const noexcept { return output_count_; }

  // Per point: a slot for the frame in progress (the span, or the carry-over without one),
  // or nullptr when its storage is full.
  LidarPoint* take_current() noexcept {
    if (attached_) return output_count_ < output_.size() ? &output_[output_count_++] : nullptr;
    return take_carry();
  }
  // Per point: a slot in the carry-over, or nullptr when full. It is the next frame's while a
  // span is attached (the caller keeps two frames apart only then).
  LidarPoint* take_carry() noexcept { return carry_count_ < carry_.size() ? &carry_[carry_count_++] : nullptr; }

  // Per block: room in the span, and its end, where `n` points are written before extend(n).
  // No span: no room.
  std::size_t output_room() const noexcept { return output_.size() - output_count_; }
  LidarPoint* output_end() const noexcept { return output_.data() + output_count_; }
  void extend(std::size_t n) noexcept { output_count_ += n; }

  // Per group of points: the frame in progress's storage and the next frame's (none without a
  // span: the carry-over then holds the frame in progress), and their new counts after.
  Storage current() noexcept {
    return attached_ ? Storage{output_.data(), output_.size(), output_count_}
                     : Storage{carry_.data(), carry_.size(), carry_count_};
  }
  Storage next() noexcept {
    return attached_ ? Storage{carry_.data(), carry_.size(), carry_count_} : Storage{};
  }
  void set_current_count(std::size_t n) noexcept { (attached_ ? output_count_ : carry_count_) = n; }
  void set_next_count(std::size_t n) noexcept {
    if (attached_) carry_count_ = n;
  }

 private:
  std::span<LidarPoint> output_;  // the frame in progress's, when attached
  bool attached_ = false;
  std::size_t output_count_ = 0;
  // The next frame's points while attached; the frame in progress's while not.
  std::vector<LidarPoint> carry_;
  std::size_t carry_count_ = 0;
};

}  // namespace sim::lidar
