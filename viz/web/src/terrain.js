// The elevation map under the robot (terrain frames: viz/README.md, "Frames"): a shaded
// height-field mesh with a vertex at each known cell's centre and the triangles whose three
// corners are known, so an unknown cell (null) leaves a hole. Coloured by height on a fixed scale
// (the same height is the same colour from one map to the next while the robot walks), lit so that
// steps and slopes show by their shading.

import * as THREE from 'three';

// Height [m] -> colour: stops of a fixed scale, clamped at both ends. Flat ground at 0 is a warm
// grey that stands out from the background and the grid; higher is ochre to brown, lower blue.
const STOPS = [
  [-0.3, new THREE.Color(0x4f7394)],
  [0.0, new THREE.Color(0xbdb4a2)],
  [0.15, new THREE.Color(0xc58a4f)],
  [0.4, new THREE.Color(0x87443a)],
];

function heightColor(z, out) {
  if (z <= STOPS[0][0]) return out.copy(STOPS[0][1]);
  for (let i = 1; i < STOPS.length; ++i) {
    if (z <= STOPS[i][0]) {
      const [z0, c0] = STOPS[i - 1];
      const [z1, c1] = STOPS[i];
      return out.copy(c0).lerp(c1, (z - z0) / (z1 - z0));
    }
  }
  return out.copy(STOPS[STOPS.length - 1][1]);
}

/** A terrain frame's shape is usable: positive finite resolution, counts and heights that agree. */
function wellFormed(f) {
  return f && Number.isInteger(f.rows) && Number.isInteger(f.cols) && f.rows > 0 && f.cols > 0 &&
    Number.isFinite(f.origin_x) && Number.isFinite(f.origin_y) &&
    Number.isFinite(f.resolution) && f.resolution > 0 &&
    Array.isArray(f.heights) && f.heights.length === f.rows * f.cols;
}

export class TerrainView {
  constructor(scene) {
    this.material = new THREE.MeshStandardMaterial({
      vertexColors: true,
      roughness: 0.95,
      metalness: 0.0,
      side: THREE.DoubleSide,
      // Behind the footholds' discs and the contact rings drawn at the same height.
      polygonOffset: true,
      polygonOffsetFactor: 1,
      polygonOffsetUnits: 1,
    });
    this.mesh = new THREE.Mesh(new THREE.BufferGeometry(), this.material);
    this.mesh.visible = false;
    this.mesh.name = 'terrain';
    scene.add(this.mesh);
    this.frame = null; // the terrain frame drawn (null: none)
    this.show = true;
    this.stats = null; // what is drawn: see describe()
  }

  /** Draws `frame` (null: no map). Rebuilds the mesh only when the frame changes. */
  set(frame) {
    if (frame === this.frame) {
      this.mesh.visible = this.show && this.stats !== null && this.stats.triangles > 0;
      return;
    }
    this.frame = frame;
    this.stats = null;
    if (!wellFormed(frame)) {
      this.mesh.visible = false;
      return;
    }
    const { rows, cols, resolution: res, heights } = frame;
    // Vertices of the known cells only (a NaN would spoil the bounds and the normals).
    const index = new Int32Array(rows * cols).fill(-1);
    let known = 0;
    for (let i = 0; i < rows * cols; ++i) {
      if (typeof heights[i] === 'number' && Number.isFinite(heights[i])) index[i] = known++;
    }
    const positions = new Float32Array(3 * known);
    const colors = new Float32Array(3 * known);
    const color = new THREE.Color();
    for (let r = 0; r < rows; ++r) {
      for (let c = 0; c < cols; ++c) {
        const k = index[r * cols + c];
        if (k < 0) continue;
        const z = heights[r * cols + c];
        positions[3 * k] = frame.origin_x + c * res;
        positions[3 * k + 1] = frame.origin_y + r * res;
        positions[3 * k + 2] = z;
        heightColor(z, color);
        colors[3 * k] = color.r;
        colors[3 * k + 1] = color.g;
        colors[3 * k + 2] = color.b;
      }
    }
    // Each square of four neighbouring centres: two triangles, or the one whose corners are known
    // when a single corner is not (counter-clockwise seen from above: normals up).
    const tris = [];
    for (let r = 0; r + 1 < rows; ++r) {
      for (let c = 0; c + 1 < cols; ++c) {
        const a = index[r * cols + c];
        const b = index[r * cols + c + 1];
        const d = index[(r + 1) * cols + c];
        const e = index[(r + 1) * cols + c + 1];
        const missing = (a < 0) + (b < 0) + (d < 0) + (e < 0);
        if (missing === 0) {
          tris.push(a, b, e, a, e, d);
        } else if (missing === 1) {
          if (a < 0) tris.push(b, e, d);
          else if (b < 0) tris.push(a, e, d);
          else if (d < 0) tris.push(a, b, e);
          else tris.push(a, b, d);
        }
      }
    }
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    geometry.setAttribute('color', new THREE.BufferAttribute(colors, 3));
    geometry.setIndex(known > 65535 ? new THREE.Uint32BufferAttribute(tris, 1)
      : new THREE.Uint16BufferAttribute(tris, 1));
    geometry.computeVertexNormals();
    geometry.computeBoundingBox();
    this.mesh.geometry.dispose();
    this.mesh.geometry = geometry;
    const box = geometry.boundingBox;
    this.stats = {
      t: frame.t,
      rows,
      cols,
      resolution: res,
      vertices: known,
      triangles: tris.length / 3,
      bounds: known > 0 ? [[box.min.x, box.min.y, box.min.z], [box.max.x, box.max.y, box.max.z]] : null,
    };
    this.mesh.visible = this.show && tris.length > 0;
  }

  /** The map's footprint on the ground, from the first cell centre to the last (the mesh's
   *  extent): {x0, y0, x1, y1} world [m], or null without a drawn map. */
  footprint() {
    if (!this.stats || !this.mesh.visible) return null;
    const f = this.frame;
    return {
      x0: f.origin_x,
      y0: f.origin_y,
      x1: f.origin_x + (f.cols - 1) * f.resolution,
      y1: f.origin_y + (f.rows - 1) * f.resolution,
    };
  }

  /** The legend's line: "100 × 100 cells of 2 cm, heights 0 to 5 cm", or null. */
  legendText() {
    if (!this.stats) return null;
    const s = this.stats;
    const cm = (m) => `${(100 * m).toFixed(Math.abs(m) < 0.1 ? 1 : 0)}`.replace(/\.0$/, '');
    const range = s.bounds ? `, heights ${cm(s.bounds[0][2])} to ${cm(s.bounds[1][2])} cm` : ', no known cell';
    return `terrain: ${s.rows} × ${s.cols} cells of ${cm(s.resolution)} cm${range}`;
  }

  /** What the hook reports: null without a map, else {t, rows, cols, resolution, vertices (known
   *  cells), triangles, bounds ([[x, y, z] min, max] of the mesh, null when no cell is known),
   *  visible}. */
  describe() {
    return this.stats ? { ...this.stats, visible: this.mesh.visible } : null;
  }
}
