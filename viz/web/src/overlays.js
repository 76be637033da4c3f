// What the controller knows and plans, drawn over the robot: the contact frames (closed or open),
// the contact forces as arrows (measured: estimated by stride-viz at the state; planned: the
// horizon's knot 0), the footholds as discs on the ground, the footholds the gait generator chose
// as rings around them coloured by where they came from, and the predicted base and feet paths
// as faint lines. Every object is made once and updated in place.

import * as THREE from 'three';

export const COLORS = {
  measured: 0xd1495b, // force at the state
  planned: 0x2f7dd1, // force the controller plans at knot 0
  base: 0x3d4650,
  contactClosed: 0x2a9d6f,
  contactOpen: 0x9aa4ad,
  // one per contact (footholds, feet paths), in the model's contact order
  perContact: [0xe0892b, 0x8e5bd1, 0x1b9aaa, 0xc2458a, 0x6a994e, 0xb5838d, 0x577590, 0xbc6c25],
  // the chosen footholds, by source (horizon_t.foothold_source)
  footholdBlind: 0x6b7480, // 0 measured, 1 blind: the ground the feet feel
  footholdMap: 0x2fa84f, // 2 the map's nominal foothold
  footholdMoved: 0xf2c12e, // 3 moved by the map to a steppable cell
  footholdBad: 0xd62828, // 4 unreachable, 5 unknown to the map (and any other number)
};

/** The colour of a chosen foothold from its source (horizon_t.foothold_source). */
export function sourceColor(source) {
  switch (source) {
    case 0:
    case 1:
      return COLORS.footholdBlind;
    case 2:
      return COLORS.footholdMap;
    case 3:
      return COLORS.footholdMoved;
    default:
      return COLORS.footholdBad;
  }
}

export function contactColor(c) {
  return COLORS.perContact[c % COLORS.perContact.length];
}

export function cssColor(hex) {
  return `#${hex.toString(16).padStart(6, '0')}`;
}

const MAX_PATH_POINTS = 512;
const MAX_FOOTHOLDS = 64;

function makeLine(color, opacity) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position',
                        new THREE.BufferAttribute(new Float32Array(MAX_PATH_POINTS * 3), 3));
  geometry.setDrawRange(0, 0);
  const material = new THREE.LineBasicMaterial({ color, transparent: true, opacity, depthWrite: false });
  const line = new THREE.Line(geometry, material);
  line.frustumCulled = false;
  return line;
}

function setLine(line, points) {
  const attr = line.geometry.getAttribute('position');
  const n = Math.min(points.length, MAX_PATH_POINTS);
  for (let i = 0; i < n; ++i) attr.setXYZ(i, points[i][0], points[i][1], points[i][2]);
  attr.needsUpdate = true;
  line.geometry.setDrawRange(0, n);
  line.visible = n >= 2;
}

/** "Nice" numbers 1, 2, 5 x 10^k at or below x. */
function niceBelow(x) {
  const p = Math.pow(10, Math.floor(Math.log10(x)));
  for (const m of [5, 2, 1]) if (m * p <= x) return m * p;
  return p;
}

export class Overlays {
  constructor(scene) {
    this.root = new THREE.Group();
    scene.add(this.root);
    this.contacts = []; // {name, marker, measured, planned}
    this.size = 0.5; // the robot's size [m], for marker sizes
    this.scale = null; // arrow length per newton [m/N], fixed at the first forces seen
    this.basePath = makeLine(COLORS.base, 0.55);
    this.root.add(this.basePath);
    this.feetPaths = [];
    this.footholds = [];
    this.footholdGroup = new THREE.Group();
    this.root.add(this.footholdGroup);
    this.chosen = []; // rings at the gait generator's footholds (plan.chosen_footholds)
    this.chosenGroup = new THREE.Group();
    this.chosenGroup.name = 'chosen-footholds';
    this.root.add(this.chosenGroup);
    this.showPlan = true;
    this.showForces = true;
  }

  /** Creates the markers for the model's contact frames; `size` is the robot's size [m]. */
  setContacts(names, size) {
    for (const c of this.contacts) {
      this.root.remove(c.marker, c.measured, c.planned);
    }
    for (const l of this.feetPaths) this.root.remove(l);
    this.size = size;
    // A ring around each contact frame, level with the ground: green when the state says the
    // contact is closed, grey when open (visible whatever the foot's own geometry).
    const r = Math.max(0.01, 0.045 * size);
    this.contacts = names.map((name, i) => {
      const marker = new THREE.Mesh(new THREE.TorusGeometry(r, 0.16 * r, 8, 32),
                                    new THREE.MeshPhongMaterial({ color: COLORS.contactOpen }));
      const measured = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 0.1,
                                             COLORS.measured);
      const planned = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 0.1,
                                            COLORS.planned);
      for (const a of [measured, planned]) {
        a.visible = false;
        a.line.material.linewidth = 2;
      }
      marker.visible = false;
      this.root.add(marker, measured, planned);
      const path = makeLine(contactColor(i), 0.6);
      this.feetPaths.push(path);
      this.root.add(path);
      return { name, marker, measured, planned };
    });
    this.feetPaths.length = names.length;
  }

  /** Chooses the arrow scale once, from the forces given (the whole log's in log mode, the
   *  first that come in live mode): the 95th percentile of their norms is drawn half a robot
   *  size long, rounded down to 1, 2 or 5 x 10^k m/N (impacts may be longer). */
  fixScale(forceLists) {
    if (this.scale !== null) return;
    const norms = [];
    for (const list of forceLists) {
      for (const f of list ?? []) {
        const n = Math.hypot(f[0], f[1], f[2]);
        if (n > 1e-9) norms.push(n);
      }
    }
    if (norms.length === 0) return;
    norms.sort((a, b) => a - b);
    const typical = norms[Math.floor(0.95 * (norms.length - 1))];
    this.scale = niceBelow((0.5 * this.size) / typical);
  }

  /** The legend's scale line, e.g. "0.1 m = 20 N"; null before the scale is known. */
  scaleText() {
    if (this.scale === null) return null;
    const len = niceBelow(0.25 * this.size);
    const newtons = len / this.scale;
    const n = newtons >= 10 ? newtons.toFixed(0) : newtons.toPrecision(2);
    const l = len >= 0.1 ? `${len} m` : `${Math.round(len * 1000)} mm`;
    return `${l} = ${n} N`;
  }

  setArrow(arrow, origin, f) {
    const norm = f ? Math.hypot(f[0], f[1], f[2]) : 0;
    if (!this.showForces || this.scale === null || !(norm > 1e-9)) {
      arrow.visible = false;
      return;
    }
    const len = norm * this.scale;
    arrow.position.copy(origin);
    arrow.setDirection(new THREE.Vector3(f[0] / norm, f[1] / norm, f[2] / norm));
    const head = Math.min(0.3 * len, 0.06 * this.size);
    arrow.setLength(len, head, 0.5 * head);
    arrow.visible = true;
  }

  /**
   * Updates the contact markers and force arrows for a state (its contact flags and measured
   * forces), the plan's knot-0 forces, the robot to read the frames' positions from.
   */
  updateContacts(robot, state, plan) {
    this.fixScale([state?.forces, plan?.forces]);
    const p = new THREE.Vector3();
    this.contacts.forEach((c, i) => {
      if (!robot.framePosition(c.name, p)) {
        c.marker.visible = c.measured.visible = c.planned.visible = false;
        return;
      }
      const closed = state?.contact?.[i] ? true : false;
      c.marker.position.copy(p);
      c.marker.material.color.setHex(closed ? COLORS.contactClosed : COLORS.contactOpen);
      c.marker.visible = true;
      this.setArrow(c.measured, p, state?.forces?.[i]);
      this.setArrow(c.planned, p, plan?.forces?.[i]);
    });
  }

  /** Updates the predicted paths and the footholds from a plan frame (null: hide them). */
  updatePlan(plan) {
    const show = this.showPlan && plan !== null;
    if (!show) {
      this.basePath.visible = false;
      for (const l of this.feetPaths) l.visible = false;
      for (const d of this.footholds) d.visible = false;
      for (const m of this.chosen) m.visible = false;
      return;
    }
    setLine(this.basePath, plan.base ?? []);
    this.feetPaths.forEach((line, c) => {
      setLine(line, (plan.feet ?? []).map((knot) => knot[c]).filter((x) => x));
    });
    const holds = plan.footholds ?? [];
    const r = Math.max(0.01, 0.035 * this.size);
    while (this.footholds.length < Math.min(holds.length, MAX_FOOTHOLDS)) {
      const disc = new THREE.Mesh(
        new THREE.CircleGeometry(r, 24),
        new THREE.MeshBasicMaterial({ color: 0xffffff, transparent: true, opacity: 0.55,
                                      depthWrite: false, side: THREE.DoubleSide }));
      this.footholds.push(disc);
      this.footholdGroup.add(disc);
    }
    this.footholds.forEach((disc, k) => {
      const h = holds[k];
      if (!h) {
        disc.visible = false;
        return;
      }
      disc.position.set(h[0], h[1], h[2] + 0.002); // just above the ground: no z-fighting
      disc.material.color.setHex(contactColor(h[3] ?? 0));
      disc.visible = true;
    });
    this.updateChosen(plan.chosen_footholds ?? []);
  }

  /** Rings around the footholds the gait generator chose ([x, y, z, contact, dt, source] each),
   *  on the ground (or the map) where they are, coloured by source. */
  updateChosen(chosen) {
    const r = Math.max(0.01, 0.035 * this.size);
    while (this.chosen.length < Math.min(chosen.length, MAX_FOOTHOLDS)) {
      const ring = new THREE.Mesh(
        new THREE.RingGeometry(1.15 * r, 1.6 * r, 32),
        new THREE.MeshBasicMaterial({ color: COLORS.footholdBlind, transparent: true, opacity: 0.9,
                                      depthWrite: false, side: THREE.DoubleSide }));
      ring.name = 'chosen-foothold';
      this.chosen.push(ring);
      this.chosenGroup.add(ring);
    }
    this.chosen.forEach((ring, k) => {
      const f = chosen[k];
      if (!f || !(Number.isFinite(f[0]) && Number.isFinite(f[1]) && Number.isFinite(f[2]))) {
        ring.visible = false;
        ring.userData = {};
        return;
      }
      ring.position.set(f[0], f[1], f[2] + 0.003); // over the discs and the terrain
      ring.material.color.setHex(sourceColor(f[5]));
      ring.userData = { contact: f[3], dt: f[4], source: f[5] };
      ring.visible = true;
    });
  }

  /** The chosen footholds drawn: [{position [x, y, z] of the ring (its z 3 mm above the
   *  foothold's), contact, dt, source, color (hex number)}], the visible rings in plan order. */
  describeChosen() {
    return this.chosen.filter((m) => m.visible).map((m) => ({
      position: [m.position.x, m.position.y, m.position.z],
      contact: m.userData.contact,
      dt: m.userData.dt,
      source: m.userData.source,
      color: m.material.color.getHex(),
    }));
  }
}
