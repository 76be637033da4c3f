// Strip charts of the controller's status (uPlot): tick latency, solve time, cost and deadline
// misses against the robot's clock, over the last WINDOW seconds up to the time shown (the
// newest status in live mode, the playhead in log mode).

import uPlot from 'uplot';

export const WINDOW = 30; // seconds shown

const SERIES = [
  { key: 'tick_ms', title: 'tick latency [ms]', stroke: '#2f7dd1' },
  { key: 'solve_ms', title: 'solve time [ms]', stroke: '#2a9d6f' },
  { key: 'cost', title: 'cost', stroke: '#8e5bd1' },
  { key: 'deadline_misses', title: 'deadline misses', stroke: '#d1495b', stepped: true, integer: true,
    range: (u, min, max) => [0, Math.max(1, Math.ceil(1.1 * max))] },
];

const INTEGER_STEPS = [1, 2, 5, 10, 20, 50, 100, 200, 500, 1e3, 2e3, 5e3, 1e4, 1e5, 1e6];

/** A y tick: three significant digits, exponent form for large or tiny values. */
function tickLabel(v) {
  if (v === 0) return '0';
  const a = Math.abs(v);
  if (a >= 1e4 || a < 1e-3) return v.toExponential(1);
  return String(Number(v.toPrecision(3)));
}

export class Charts {
  constructor(container) {
    this.container = container;
    this.plots = SERIES.map((s) => {
      const div = document.createElement('div');
      div.className = 'chart';
      container.appendChild(div);
      const plot = new uPlot({
        title: s.title,
        width: this.width(),
        height: 120,
        legend: { show: false },
        cursor: { drag: { x: false, y: false }, points: { show: false } },
        scales: { x: { time: false }, ...(s.range ? { y: { range: s.range } } : {}) },
        series: [
          {},
          {
            label: s.title,
            stroke: s.stroke,
            width: 1.5,
            points: { show: false },
            ...(s.stepped ? { paths: uPlot.paths.stepped({ align: 1 }) } : {}),
          },
        ],
        axes: [
          { size: 28, font: '11px sans-serif', values: (u, v) => v.map((x) => x.toFixed(1)) },
          { font: '11px sans-serif', values: (u, v) => v.map(tickLabel),
            // wide enough for the longest label (about 6.5 px a character at 11 px)
            size: (u, values) => 16 + 6.5 * Math.max(4, ...(values ?? []).map((x) => x.length)),
            ...(s.integer ? { incrs: INTEGER_STEPS } : {}) },
        ],
      }, [[], []], div);
      return { s, plot };
    });
    new ResizeObserver(() => this.resize()).observe(container);
  }

  width() {
    return Math.max(160, this.container.clientWidth - 8);
  }

  resize() {
    const w = this.width();
    for (const { plot } of this.plots) plot.setSize({ width: w, height: 120 });
  }

  /** Shows the statuses `frames` (oldest first) up to time `now` [s]. */
  show(frames, now) {
    const t = frames.map((f) => f.t);
    const from = frames.length > 0 ? Math.max(frames[0].t, now - WINDOW) : now - WINDOW;
    const to = Math.max(now, from + 1); // at least a second shown
    for (const { s, plot } of this.plots) {
      const y = frames.map((f) => (Number.isFinite(f[s.key]) ? f[s.key] : null));
      plot.setData([t, y], false);
      plot.setScale('x', { min: from, max: to });
    }
  }
}
