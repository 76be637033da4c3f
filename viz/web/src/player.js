// Log mode's player: play / pause, speed (0.25x to 4x) and a timeline to scrub, all in the page.
// The playhead is a robot-clock time in [t0, t1], the first and last frame of the log; the
// timeline and the clock show it from the log's start.

export class Player {
  constructor(t0, t1, show) {
    this.t0 = t0;
    this.t1 = t1;
    this.show = show; // show(t, fromUser)
    this.time = t0;
    this.playing = false;
    this.speed = 1;
    this.lastNow = null;
    this.el = {
      bar: document.getElementById('player'),
      play: document.getElementById('play'),
      speed: document.getElementById('speed'),
      timeline: document.getElementById('timeline'),
      clock: document.getElementById('clock'),
    };
    this.el.bar.hidden = false;
    this.el.timeline.max = String(this.duration());
    this.el.play.addEventListener('click', () => this.toggle());
    this.el.speed.addEventListener('change', () => {
      this.speed = Number(this.el.speed.value);
    });
    this.el.timeline.addEventListener('input', () => {
      this.seek(Number(this.el.timeline.value), { fromUser: true, keepPlaying: true });
    });
    window.addEventListener('keydown', (e) => {
      if (e.code === 'Space' && e.target.tagName !== 'INPUT' && e.target.tagName !== 'SELECT' &&
          e.target.tagName !== 'BUTTON') {
        e.preventDefault();
        this.toggle();
      }
    });
    this.paint();
  }

  duration() {
    return Math.max(0, this.t1 - this.t0);
  }

  toggle() {
    if (this.playing) {
      this.pause();
    } else {
      if (this.time >= this.t1) this.seek(0, { keepPlaying: true }); // from the start again
      this.playing = true;
      this.lastNow = null;
      this.paint();
    }
  }

  pause() {
    this.playing = false;
    this.paint();
  }

  /** Moves the playhead to `offset` seconds from the log's start (clamped) and shows it now. */
  seek(offset, { fromUser = false, keepPlaying = false } = {}) {
    if (!keepPlaying) this.pause();
    const d = this.duration();
    const o = Math.min(Math.max(Number.isFinite(offset) ? offset : 0, 0), d);
    this.time = this.t0 + o;
    this.lastNow = null;
    this.show(this.time, fromUser);
    this.paint();
  }

  /** Called every animation frame: advances the playhead while playing. */
  tick(now) {
    if (!this.playing) return;
    if (this.lastNow !== null) {
      this.time = Math.min(this.t1, this.time + ((now - this.lastNow) / 1000) * this.speed);
      this.show(this.time, false);
      if (this.time >= this.t1) this.playing = false;
      this.paint();
    }
    this.lastNow = now;
  }

  paint() {
    const o = this.time - this.t0;
    this.el.play.innerHTML = this.playing ? '&#10074;&#10074;' : '&#9654;';
    this.el.play.setAttribute('aria-label', this.playing ? 'pause' : 'play');
    if (document.activeElement !== this.el.timeline || !this.playing) {
      this.el.timeline.value = String(o);
    }
    this.el.clock.textContent = `${o.toFixed(3)} / ${this.duration().toFixed(3)} s`;
  }
}
