// The status line: robot, mode (live URL and connection, or the log file), gait, command, the
// time shown, counters (tick, dropped frames, rejected messages) and warnings (the model hash
// stride-viz reports, a URDF that does not match the model, meshes that did not load).

const fmt = (x, digits = 2) => (Number.isFinite(x) ? x.toFixed(digits) : '–');

export class StatusLine {
  constructor() {
    this.el = {
      robot: document.getElementById('st-robot'),
      mode: document.getElementById('st-mode'),
      gait: document.getElementById('st-gait'),
      command: document.getElementById('st-command'),
      time: document.getElementById('st-time'),
      counters: document.getElementById('st-counters'),
      warning: document.getElementById('st-warning'),
      message: document.getElementById('message'),
    };
    this.info = {};
    this.connection = null;
    this.warnings = new Map(); // key -> text
    this.lastFrameText = '';
  }

  setInfo(info) {
    this.info = info;
    // stride-viz's warnings (the model hash of the messages against the robot it loaded, ...):
    // `warnings`, a list, or `warning`, one text.
    const list = [].concat(info.warnings ?? [], info.warning ?? []).filter((w) => w);
    this.warn('info', list.length ? list.join(' · ') : null);
    this.paintMode();
    this.paintCounters(null);
  }

  setConnection(state, delayMs) {
    this.connection = state === 'open' ? 'connected'
      : `reconnecting in ${(delayMs / 1000).toFixed(1)} s`;
    this.paintMode();
  }

  paintMode() {
    const i = this.info;
    let text;
    if (i.mode === 'log') {
      text = `log ${basename(i.log ?? '')}`;
    } else if (i.mode === 'live') {
      text = `live ${i.url ?? ''}${this.connection ? ` (${this.connection})` : ''}`;
    } else {
      text = '';
    }
    this.el.mode.textContent = text;
  }

  setModel(model) {
    this.el.robot.textContent = model.robot ?? 'robot';
    this.el.robot.title = `model hash ${model.model_hash ?? '?'}; nq ${model.nq}, nv ${model.nv}`;
    this.warn('hash', model.warning || null);
  }

  /** The state shown and the status at its time (either may be null). */
  setFrame(state, status) {
    this.el.gait.textContent = status?.gait ? `gait ${status.gait}` : '';
    const c = status?.command;
    this.el.command.textContent = Array.isArray(c) && c.length >= 4
      ? `command vx ${fmt(c[0])} vy ${fmt(c[1])} m/s, yaw ${fmt(c[2])} rad/s, height ${fmt(c[3], 3)} m`
      : '';
    this.el.time.textContent = state ? `t ${fmt(state.t, 3)} s` : 'no state';
    this.paintCounters(status);
  }

  paintCounters(status) {
    if (status !== null) this.lastStatus = status;
    const s = this.lastStatus;
    const parts = [];
    if (s) {
      parts.push(`tick ${s.tick ?? '–'}`);
      parts.push(`misses ${s.deadline_misses ?? '–'}`);
      if (s.rejected) parts.push(`rejected ${s.rejected}`);
    }
    parts.push(`dropped frames ${this.info.dropped_frames ?? 0}`);
    this.el.counters.textContent = parts.join(' · ');
  }

  /** Sets (text) or clears (null) the warning under `key`; all warnings show, joined. */
  warn(key, text) {
    if (text) {
      if (this.warnings.get(key) === text) return;
      if (!this.warnings.has(key)) console.warn(`stride-viz: ${text}`);
      this.warnings.set(key, text);
    } else if (!this.warnings.delete(key)) {
      return;
    }
    const all = [...this.warnings.values()];
    this.el.warning.hidden = all.length === 0;
    this.el.warning.textContent = all.length ? `⚠ ${all.join(' · ')}` : '';
    this.el.warning.title = all.join('\n');
  }

  /** A message over the view (loading, connection lost, errors); null hides it. */
  message(text) {
    this.el.message.hidden = !text;
    this.el.message.textContent = text ?? '';
  }
}

function basename(path) {
  return String(path).split('/').pop();
}
