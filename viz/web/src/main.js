// stride-viz's page: asks stride-viz which mode it runs in (GET api/info), then either follows the
// live session over the WebSocket ws or plays the log of GET api/log. The frames are described
// in viz/README.md; everything is fetched from stride-viz (no other host, no CDN).

import * as THREE from 'three';
import { SceneView } from './scene.js';
import { loadRobot } from './robot.js';
import { Overlays, COLORS, contactColor, cssColor } from './overlays.js';
import { TerrainView } from './terrain.js';
import { Charts, WINDOW } from './charts.js';
import { Track } from './track.js';
import { connect, wsUrl } from './live.js';
import { Player } from './player.js';
import { StatusLine } from './status.js';
import { installHook } from './hook.js';

const LIVE_SECONDS = WINDOW; // live mode keeps the last 30 s of frames
const LIVE_MAX_FRAMES = 20000; // and never more than this many of one type
const CHART_PERIOD_MS = 250; // charts redrawn at most 4 times a second while time runs
const LIVE_MAX_MAPS = 4; // live mode draws the newest map: a few kept (each ~50 kB of numbers)

class Viewer {
  constructor() {
    this.view = new SceneView(document.getElementById('view'));
    this.overlays = new Overlays(this.view.scene);
    this.terrain = new TerrainView(this.view.scene);
    this.charts = new Charts(document.getElementById('charts'));
    this.status = new StatusLine();
    this.mode = null;
    this.info = {};
    this.model = null;
    this.robot = null;
    this.robotLoading = null;
    this.framed = false;
    this.ready = false;
    this.framesReceived = 0;
    this.time = null; // robot-clock time shown [s]
    this.shown = null; // the state frame shown
    this.dirty = false;
    this.chartsDirty = false;
    this.lastChartMs = 0;
    const bounds = { maxAge: Infinity, maxCount: Infinity };
    this.states = new Track(bounds);
    this.plans = new Track(bounds);
    this.statuses = new Track(bounds);
    this.terrains = new Track(bounds);
    this.player = null;
    this.bindOptions();
    paintLegend();
  }

  bindOptions() {
    const check = (id, apply) => {
      const box = document.getElementById(id);
      box.addEventListener('change', () => {
        apply(box.checked);
        this.dirty = true;
      });
    };
    check('opt-follow', (on) => { this.view.follow = on; });
    check('opt-plan', (on) => { this.overlays.showPlan = on; });
    check('opt-forces', (on) => { this.overlays.showForces = on; });
    check('opt-terrain', (on) => { this.terrain.show = on; });
  }

  async start() {
    const info = await fetchJson('api/info');
    this.setInfo(info);
    if (info.mode === 'log') {
      await this.startLog();
    } else {
      this.startLive();
    }
    const loop = (now) => {
      this.tick(now);
      requestAnimationFrame(loop);
    };
    requestAnimationFrame(loop);
  }

  // ---- log mode: the whole log at once, played here ----

  async startLog() {
    this.mode = 'log';
    this.status.message('loading the log…');
    const doc = await fetchJson('api/log');
    if (doc.info) this.setInfo(doc.info);
    const frames = Array.isArray(doc.frames) ? doc.frames : [];
    this.framesReceived = frames.length;
    this.states.setAll(frames.filter((f) => f.type === 'state'));
    this.plans.setAll(frames.filter((f) => f.type === 'plan'));
    this.statuses.setAll(frames.filter((f) => f.type === 'status'));
    this.terrains.setAll(frames.filter((f) => f.type === 'terrain'));
    const model = doc.model ?? frames.find((f) => f.type === 'model');
    if (!model) throw new Error('the log has no robot model');
    await this.setModel(model);
    // The arrows' scale from the whole log's forces (live mode: the first that come).
    this.overlays.fixScale([...this.states.frames, ...this.plans.frames].map((f) => f.forces));
    let t0 = Infinity;
    let t1 = -Infinity;
    for (const f of frames) {
      if (Number.isFinite(f.t)) {
        t0 = Math.min(t0, f.t);
        t1 = Math.max(t1, f.t);
      }
    }
    if (t0 > t1) t0 = t1 = 0;
    this.player = new Player(t0, t1, (t) => {
      // While playing, the charts follow at their own pace (tick); a seek redraws them now.
      const playing = this.player !== null && this.player.playing;
      this.showAt(t, { charts: !playing });
      if (playing) this.chartsDirty = true;
    });
    this.status.message(null);
    if (this.states.length === 0) this.status.message('the log has no robot state');
    this.showAt(t0, { charts: true });
    this.ready = this.robot !== null;
  }

  // ---- live mode: frames over the WebSocket, the last 30 s kept ----

  startLive() {
    this.mode = 'live';
    const bounds = { maxAge: LIVE_SECONDS, maxCount: LIVE_MAX_FRAMES };
    this.states = new Track(bounds);
    this.plans = new Track(bounds);
    this.statuses = new Track(bounds);
    this.terrains = new Track({ maxAge: LIVE_SECONDS, maxCount: LIVE_MAX_MAPS });
    this.status.message('connecting…');
    connect(wsUrl('ws'), {
      onFrame: (f) => this.onLiveFrame(f),
      onState: (state, delayMs) => {
        this.status.setConnection(state, delayMs);
        if (state === 'open') {
          this.status.message(this.model ? null : 'waiting for the robot model…');
        } else {
          this.status.message(`stride-viz is not answering; trying again in ${(delayMs / 1000).toFixed(1)} s`);
        }
      },
    });
  }

  onLiveFrame(f) {
    this.framesReceived += 1;
    switch (f.type) {
      case 'info':
        this.setInfo(f);
        return;
      case 'model':
        this.setModel(f).catch((e) => this.fail(e));
        return;
      case 'state':
        this.states.push(f);
        break;
      case 'plan':
        this.plans.push(f);
        break;
      case 'status':
        this.statuses.push(f);
        this.chartsDirty = true;
        break;
      case 'terrain':
        // Drawn at the view's time like the rest; not a reason to move that time (a map may come
        // before any state, or after the robot stopped).
        this.terrains.push(f);
        if (this.time === null) this.time = f.t;
        this.dirty = true;
        return;
      default:
        return; // a frame type this page does not know: ignored
    }
    // The view follows the newest frame.
    const newest = Math.max(...[this.states, this.plans, this.statuses]
      .map((tr) => tr.newest()?.t ?? -Infinity));
    this.time = newest;
    this.dirty = true;
  }

  // ---- shared ----

  setInfo(info) {
    this.info = { ...this.info, ...info };
    this.status.setInfo(this.info);
  }

  /** A model frame: loads the robot's URDF the first time, binds its joints to the model. */
  async setModel(model) {
    const same = this.model && this.model.model_hash === model.model_hash &&
      this.model.robot === model.robot;
    this.model = model;
    this.status.setModel(model);
    if (same && this.robot) return;
    if (!this.robot) {
      if (!this.robotLoading) {
        this.robotLoading = loadRobot(model.urdf || 'robot.urdf',
                                      (w) => this.status.warn('meshes', w));
      }
      let robot;
      try {
        robot = await this.robotLoading;
      } finally {
        this.robotLoading = null;
      }
      if (this.robot) return; // another model frame finished first
      this.robot = robot;
      this.view.scene.add(robot.urdf);
    }
    const problems = this.robot.bind(this.model);
    this.status.warn('model', problems.length ? `the URDF does not match the model: ${problems.join('; ')}` : null);
    this.framed = false;
    this.overlays.setContacts(this.model.contacts ?? [], this.robotSize());
    paintContactLegend(this.model.contacts ?? []);
    this.dirty = true;
    if (this.mode === 'live') {
      this.ready = true;
      this.status.message(null);
    }
  }

  robotSize() {
    if (!this.robot) return 0.5;
    const s = this.robot.box().getSize(new THREE.Vector3());
    return Math.max(0.1, Math.max(s.x, s.y, s.z));
  }

  /** Shows the state, plan and status at robot-clock time t (synchronously). */
  showAt(t, { charts = false } = {}) {
    this.time = t;
    this.dirty = false;
    const state = this.states.shownAt(t);
    const plan = this.plans.at(t);
    const status = this.statuses.at(t);
    // The map at t: the newest at or before t, else the first (the ground was there before it was
    // measured).
    this.terrain.set(this.terrains.shownAt(t));
    this.view.setGroundHole(this.terrain.footprint());
    const legend = document.getElementById('legend-terrain');
    legend.textContent = this.terrain.legendText() ?? '';
    legend.hidden = legend.textContent === '';
    this.shown = state;
    if (this.robot && state) {
      this.robot.apply(state.q);
      if (!this.framed) {
        this.overlays.size = this.robotSize();
        this.view.frame(this.robot.box());
        this.framed = true;
      }
      this.view.followPoint(this.robot.basePosition(new THREE.Vector3()));
    }
    if (this.robot) {
      this.overlays.updateContacts(this.robot, state, plan);
      this.overlays.updatePlan(plan);
      document.getElementById('legend-scale').textContent =
        `arrows: ${this.overlays.scaleText() ?? 'no forces yet'}`;
    }
    this.status.setFrame(state, status);
    if (charts) this.updateCharts(t);
  }

  updateCharts(t) {
    this.lastChartMs = performance.now();
    this.chartsDirty = false;
    this.charts.show(this.statuses.range(t - WINDOW, t), t);
  }

  tick(now) {
    if (this.player) this.player.tick(now); // may call showAt
    if (this.dirty && this.time !== null) this.showAt(this.time);
    if (this.chartsDirty && this.time !== null && now - this.lastChartMs > CHART_PERIOD_MS) {
      this.updateCharts(this.time);
    }
    this.view.render();
  }

  fail(e) {
    console.error('stride-viz:', e);
    this.status.message(`error: ${e.message ?? e}`);
  }

  snapshot() {
    const plan = this.time !== null ? this.plans.at(this.time) : null;
    const base = this.robot ? this.robot.basePosition(new THREE.Vector3()) : null;
    return {
      t: this.shown ? this.shown.t : null,
      joint_names: this.robot ? this.robot.jointNames() : [],
      joint_angles: this.robot ? this.robot.jointAngles() : [],
      urdf_joint_count: this.robot ? this.robot.movable.length : 0,
      frames_received: this.framesReceived,
      mode: this.mode,
      base: base ? [base.x, base.y, base.z] : null,
      plan_t: plan ? plan.t : null,
      planned_forces: plan?.forces ?? [],
      force_scale: this.overlays.scaleText(),
      terrain: this.terrain.describe(),
      chosen_footholds: this.overlays.describeChosen(),
    };
  }

  /** The hook's camera(view): looks at view.target from view.position (world [x, y, z], metres)
   *  and draws at once; returns where the camera is (SceneView.describe). */
  camera(view) {
    if (view !== undefined && view !== null) {
      const point = (p, name) => {
        if (!Array.isArray(p) || p.length !== 3 || !p.every(Number.isFinite)) {
          throw new Error(`camera: ${name} must be [x, y, z] (finite numbers)`);
        }
        return new THREE.Vector3(p[0], p[1], p[2]);
      };
      this.view.aim(point(view.target, 'target'), point(view.position, 'position'));
      this.view.render();
    }
    return this.view.describe();
  }
}

async function fetchJson(path) {
  const res = await fetch(path, { cache: 'no-store' });
  if (!res.ok) throw new Error(`GET ${path}: ${res.status} ${res.statusText}`);
  return res.json();
}

function paintLegend() {
  for (const el of document.querySelectorAll('#legend [data-color]')) {
    el.style.setProperty('--c', cssColor(COLORS[el.dataset.color]));
  }
}

function paintContactLegend(names) {
  const box = document.getElementById('legend-contacts');
  box.replaceChildren(...names.map((name, c) => {
    const row = document.createElement('span');
    row.className = 'contact';
    const i = document.createElement('i');
    i.className = 'line';
    i.style.setProperty('--c', cssColor(contactColor(c)));
    row.append(i, name);
    return row;
  }));
  box.title = 'predicted feet paths and footholds (discs), one colour per contact';
}

const viewer = new Viewer();
installHook(viewer);
viewer.start().catch((e) => viewer.fail(e));
