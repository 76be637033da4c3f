// Frames of one type in time order, and the rule that picks the one shown at a time.
//
// A Track holds frames sorted by t. In log mode it holds the whole log; in live mode it is a
// bounded ring buffer: frames older than `maxAge` seconds before the newest are dropped, and
// never more than `maxCount` are kept, so memory stays bounded however long the page runs.

export class Track {
  constructor({ maxAge = Infinity, maxCount = Infinity } = {}) {
    this.maxAge = maxAge;
    this.maxCount = maxCount;
    this.frames = [];
    this.start = 0; // index of the oldest kept frame: dropping from the front is a move of start
  }

  get length() {
    return this.frames.length - this.start;
  }

  get(i) {
    return this.frames[this.start + i];
  }

  first() {
    return this.length > 0 ? this.frames[this.start] : null;
  }

  newest() {
    return this.length > 0 ? this.frames[this.frames.length - 1] : null;
  }

  clear() {
    this.frames = [];
    this.start = 0;
  }

  /** Appends a frame. A frame older than the newest means the robot's clock went back (a new
   *  session): the track starts over from it. */
  push(frame) {
    const last = this.newest();
    if (last !== null && frame.t < last.t) this.clear();
    this.frames.push(frame);
    this.prune();
  }

  /** Sets the whole content (log mode); the frames are sorted by t, stable for equal stamps. */
  setAll(frames) {
    this.frames = frames.map((f, i) => [f, i]).sort((a, b) => a[0].t - b[0].t || a[1] - b[1])
      .map(([f]) => f);
    this.start = 0;
  }

  prune() {
    const newest = this.newest();
    if (newest === null) return;
    while (this.length > this.maxCount || (this.length > 1 && this.first().t < newest.t - this.maxAge)) {
      this.start += 1;
    }
    // Compact now and then so the array does not grow with the dropped frames.
    if (this.start > 1024 && this.start * 2 > this.frames.length) {
      this.frames = this.frames.slice(this.start);
      this.start = 0;
    }
  }

  /** Index (0-based from the oldest kept) of the newest frame with t <= time; -1 if none. */
  indexAt(time) {
    let lo = 0;
    let hi = this.length - 1;
    if (hi < 0 || this.get(0).t > time) return -1;
    while (lo < hi) { // invariant: get(lo).t <= time
      const mid = (lo + hi + 1) >> 1;
      if (this.get(mid).t <= time) lo = mid; else hi = mid - 1;
    }
    return lo;
  }

  /** The newest frame with t <= time, or null when every frame is later. */
  at(time) {
    const i = this.indexAt(time);
    return i < 0 ? null : this.get(i);
  }

  /** The state shown at `time`: the newest frame with t <= time, the first one when `time` is
   *  before every frame (test/lcmlog.mjs's stateAt applies the same rule to the log). */
  shownAt(time) {
    return this.at(time) ?? this.first();
  }

  /** Frames with from <= t <= to, oldest first. */
  range(from, to) {
    const out = [];
    let i = Math.max(0, this.indexAt(from));
    for (; i < this.length; ++i) {
      const f = this.get(i);
      if (f.t > to) break;
      if (f.t >= from) out.push(f);
    }
    return out;
  }
}
