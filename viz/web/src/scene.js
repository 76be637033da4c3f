// The 3D view: renderer, a z-up world (the robot's: x forward, z up), lights, the ground grid
// (cut out where an elevation map is drawn), the camera with OrbitControls, framing the robot and
// following it.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

export class SceneView {
  constructor(container) {
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    container.appendChild(this.renderer.domElement);

    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0xe9edf1);
    // The grid fades into the background with distance (set by frame()).
    this.scene.fog = new THREE.Fog(0xe9edf1, 4, 16);

    this.camera = new THREE.PerspectiveCamera(40, 1, 0.01, 500);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(1.2, -1.6, 0.9);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.enableDamping = false;
    this.controls.target.set(0, 0, 0.2);
    this.controls.update();

    const hemi = new THREE.HemisphereLight(0xffffff, 0x8d8d8d, 2.0);
    hemi.position.set(0, 0, 1);
    this.scene.add(hemi);
    this.sun = new THREE.DirectionalLight(0xffffff, 2.2);
    this.sun.position.set(2, -3, 5);
    this.scene.add(this.sun);

    // The ground: 1 m and 0.1 m grids on z = 0, moved in whole metres to stay under the robot.
    // Not THREE.GridHelper: its lines run the grid's whole width, so the camera (inside the
    // grid, just above it) has every nearby line pass behind it, and some rasterizers
    // (Chromium's SwiftShader/ANGLE, the browser test's and headless viewers') drop a GL line
    // with an end behind the camera instead of clipping it: the grid under the robot vanished
    // and only its far part was drawn. Lines cut into one-cell segments stay drawn.
    this.ground = new THREE.Group();
    const fine = makeGrid(10, 100, 0xc3c9cf, 0xd3d8dd);
    const coarse = makeGrid(40, 40, 0x8f99a3, 0xa7b0b8);
    // Where an elevation map is drawn (terrain.js), the flat grid is not the ground: its
    // fragments inside the map's footprint (world x0, y0, x1, y1; empty when x0 > x1) are
    // discarded, so the map's holes show nothing rather than a floor that may not be there.
    this.groundHole = { value: new THREE.Vector4(1, 1, -1, -1) };
    for (const g of [fine, coarse]) {
      g.material.depthWrite = false;
      cutOut(g.material, this.groundHole);
      this.ground.add(g);
    }
    fine.position.z = -0.0005;
    this.scene.add(this.ground);
    const axes = new THREE.AxesHelper(0.15);
    axes.position.z = 0.0005;
    this.scene.add(axes);

    this.followTarget = null; // the last followed point (world), or null before the first
    this.follow = true;

    this.resize();
    new ResizeObserver(() => this.resize()).observe(container);
  }

  resize() {
    const w = Math.max(1, this.container.clientWidth);
    const h = Math.max(1, this.container.clientHeight);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
  }

  /** Points the camera at `box` (a THREE.Box3 of the robot) from the front right, above. */
  frame(box) {
    const center = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3());
    const radius = Math.max(0.1, 0.5 * size.length());
    // The narrower of the vertical and horizontal fields of view.
    const vfov = THREE.MathUtils.degToRad(this.camera.fov);
    const fov = Math.min(vfov, 2 * Math.atan(Math.tan(vfov / 2) * this.camera.aspect));
    const distance = (radius / Math.sin(fov / 2)) * 1.6;
    const dir = new THREE.Vector3(0.75, -1.0, 0.55).normalize();
    this.aim(center, center.clone().addScaledVector(dir, distance));
    this.followTarget = center.clone();
  }

  /** Looks at `target` from `position` (THREE.Vector3, world): clipping planes and fog follow
   *  the distance. While "follow" is on, the camera then moves with the base from there. */
  aim(target, position) {
    const distance = Math.max(1e-3, target.distanceTo(position));
    this.controls.target.copy(target);
    this.camera.position.copy(position);
    this.camera.near = Math.max(0.005, distance / 200);
    this.camera.far = distance * 200;
    this.camera.updateProjectionMatrix();
    this.scene.fog.near = 3 * distance;
    this.scene.fog.far = 12 * distance;
    this.controls.update();
  }

  /** Where the camera is: target and position (world), vertical field of view [deg], and the
   *  canvas's size in CSS pixels and aspect. */
  describe() {
    const v = (p) => [p.x, p.y, p.z];
    return {
      target: v(this.controls.target),
      position: v(this.camera.position),
      fov: this.camera.fov,
      aspect: this.camera.aspect,
      width: this.container.clientWidth,
      height: this.container.clientHeight,
    };
  }

  /** Moves the camera with the robot: the target and the camera shift by the robot's motion,
   *  keeping the user's angle and distance. The grid moves in whole metres. */
  followPoint(p) {
    this.ground.position.set(Math.round(p.x), Math.round(p.y), 0);
    if (!this.follow) {
      this.followTarget = null;
      return;
    }
    if (this.followTarget !== null) {
      const delta = new THREE.Vector3(p.x - this.followTarget.x, p.y - this.followTarget.y, 0);
      this.controls.target.add(delta);
      this.camera.position.add(delta);
      this.controls.update();
    }
    this.followTarget = new THREE.Vector3(p.x, p.y, p.z);
  }

  /** The flat grid leaves out this rectangle ({x0, y0, x1, y1} world [m]; null: none). */
  setGroundHole(rect) {
    if (rect) this.groundHole.value.set(rect.x0, rect.y0, rect.x1, rect.y1);
    else this.groundHole.value.set(1, 1, -1, -1);
  }

  render() {
    this.renderer.render(this.scene, this.camera);
  }
}

/** Makes `material` (a LineBasicMaterial) discard its fragments whose world x, y lie inside
 *  `hole.value` (x0, y0, x1, y1). */
function cutOut(material, hole) {
  material.onBeforeCompile = (shader) => {
    shader.uniforms.groundHole = hole;
    shader.vertexShader = `varying vec2 vGroundXY;\n${shader.vertexShader.replace(
      '#include <project_vertex>',
      '#include <project_vertex>\n  vGroundXY = (modelMatrix * vec4(transformed, 1.0)).xy;')}`;
    shader.fragmentShader = `uniform vec4 groundHole;\nvarying vec2 vGroundXY;\n${shader.fragmentShader.replace(
      'void main() {',
      'void main() {\n  if (all(greaterThan(vGroundXY, groundHole.xy)) && all(lessThan(vGroundXY, groundHole.zw))) discard;')}`;
  };
}

/** A grid on z = 0 like THREE.GridHelper's (size, divisions, centre-line colour, line colour),
 *  in the x-y plane, every line made of one-cell segments (see the ground in SceneView). */
function makeGrid(size, divisions, centerColor, color) {
  const step = size / divisions;
  const half = size / 2;
  const positions = [];
  const colors = [];
  const c0 = new THREE.Color(centerColor);
  const c1 = new THREE.Color(color);
  for (let i = 0; i <= divisions; ++i) {
    const k = -half + i * step;
    const c = 2 * i === divisions ? c0 : c1;
    for (let j = 0; j < divisions; ++j) {
      const a = -half + j * step;
      const b = a + step;
      positions.push(a, k, 0, b, k, 0, k, a, 0, k, b, 0);
      for (let v = 0; v < 4; ++v) colors.push(c.r, c.g, c.b);
    }
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
  geometry.setAttribute('color', new THREE.Float32BufferAttribute(colors, 3));
  return new THREE.LineSegments(geometry,
                                new THREE.LineBasicMaterial({ vertexColors: true, toneMapped: false }));
}
