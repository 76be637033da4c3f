// The robot: its URDF drawn by urdf-loader (visual geometry: boxes, cylinders, spheres, and meshes
// when their files load), posed from a configuration q in wire order (controller/README.md,
// "Wire contract"): q[0:3] base position, q[3:7] base quaternion x y z w for a floating base, then
// each joint's coordinate at the model's idx_q, set on the URDF joint of the same name.

import * as THREE from 'three';
import URDFLoader from 'urdf-loader';
import { STLLoader } from 'three/addons/loaders/STLLoader.js';
import { ColladaLoader } from 'three/addons/loaders/ColladaLoader.js';
import { OBJLoader } from 'three/addons/loaders/OBJLoader.js';

/** URDF colours are written as sRGB; three's materials take linear values (once per material). */
function linearize(material) {
  if (material && material.color && !material.userData.strideLinear) {
    material.color.convertSRGBToLinear();
    material.userData.strideLinear = true;
  }
}

/**
 * Loads the URDF at `url` (fetched here, parsed by urdf-loader). A mesh file name is resolved
 * against the URDF's URL as written (stride-viz rewrites them to /robot/files/<index>/<name>).
 * Meshes load in the background; those that fail (missing, unknown format) are reported through
 * `onWarning(summary, failures)`, and the robot's skeleton (joints and the segments between them) is drawn so the
 * robot stays visible.
 */
export async function loadRobot(url, onWarning) {
  const urdfUrl = new URL(url, window.location.href);
  const res = await fetch(urdfUrl, { cache: 'no-store' });
  if (!res.ok) throw new Error(`the robot's URDF (${url}): ${res.status} ${res.statusText}`);
  const text = await res.text();

  const manager = new THREE.LoadingManager();
  const loader = new URDFLoader(manager);
  loader.parseVisual = true;
  loader.parseCollision = false;
  let view = null;
  let meshes = 0;
  const failures = [];
  loader.loadMeshCb = (path, mgr, material, done) => {
    const href = new URL(path, urdfUrl).href;
    const name = decodeURIComponent(href.split('/').pop());
    meshes += 1;
    linearize(material);
    const failed = (why) => {
      failures.push(`${name}: ${why}`);
      onWarning(`${failures.length} of ${meshes} meshes not shown (${failures[0]}` +
                `${failures.length > 1 ? ', …' : ''}): the skeleton stands in`, failures);
      if (view) view.skeleton.visible = true;
      done(null); // no error object: the robot stays, without this mesh
    };
    const ext = (name.match(/\.([a-z0-9]+)$/i)?.[1] ?? '').toLowerCase();
    const onError = (e) => {
      const status = String(e?.message ?? '').match(/responded with (\d+)/);
      failed(status ? `HTTP ${status[1]}` : (e?.message ?? 'not loaded'));
    };
    if (ext === 'stl') {
      new STLLoader(mgr).load(href, (geometry) => {
        geometry.computeVertexNormals();
        done(new THREE.Mesh(geometry, material));
      }, undefined, onError);
    } else if (ext === 'dae') {
      new ColladaLoader(mgr).load(href, (dae) => done(dae.scene), undefined, onError);
    } else if (ext === 'obj') {
      new OBJLoader(mgr).load(href, (obj) => {
        obj.traverse((c) => { if (c.isMesh) c.material = material; });
        done(obj);
      }, undefined, onError);
    } else {
      failed(`no loader for .${ext}`);
    }
  };
  // '' as the working path: file names reach loadMeshCb as written, resolved there.
  view = new RobotView(loader.parse(text, ''));
  if (failures.length > 0) view.skeleton.visible = true;
  return view;
}

export class RobotView {
  constructor(urdf) {
    this.urdf = urdf;
    let visuals = 0;
    urdf.traverse((c) => {
      if (c.isURDFVisual) visuals += 1;
      if (c.isMesh) linearize(c.material);
    });
    // The skeleton: a sphere at each joint and a rod from its parent link's origin, drawn in the
    // links' frames so it moves with the joints; shown when the URDF has no visual geometry or
    // a mesh did not load.
    this.skeleton = makeSkeleton(urdf);
    this.skeleton.visible = visuals === 0;
    // Every movable joint of the URDF, whatever the model says (urdf_joint_count).
    this.movable = Object.values(urdf.joints).filter((j) => j.jointType !== 'fixed');
    for (const j of this.movable) j.ignoreLimits = true; // show the state, not a clamped one
    this.bound = [];
    this.floating = false;
    this.problems = [];
  }

  /**
   * Binds the model frame's joints (wire order) to the URDF's joints by name. Returns the
   * problems found (a model joint the URDF does not have, or a count that differs): the URDF
   * and the model on the wire are not the same robot, shown as a warning.
   */
  bind(model) {
    this.floating = model.floating ?? model.joints.some((j) => j.type === 'free-flyer');
    this.bound = [];
    const problems = [];
    for (const j of model.joints) {
      if (j.type === 'free-flyer') continue;
      const joint = this.urdf.joints[j.name];
      if (!joint || joint.jointType === 'fixed') problems.push(`joint ${j.name} is not in the URDF`);
      this.bound.push({ name: j.name, idx: j.idx_q, joint: joint && joint.jointType !== 'fixed' ? joint : null });
    }
    if (this.bound.length !== this.movable.length) {
      problems.push(`the model has ${this.bound.length} joints, the URDF ${this.movable.length}`);
    }
    this.problems = problems;
    return problems;
  }

  /** Poses the robot at configuration q (wire order). */
  apply(q) {
    const u = this.urdf;
    if (this.floating && q.length >= 7) {
      u.position.set(q[0], q[1], q[2]);
      u.quaternion.set(q[3], q[4], q[5], q[6]);
      if (Math.abs(u.quaternion.lengthSq() - 1) > 1e-6) u.quaternion.normalize();
    }
    for (const b of this.bound) {
      if (b.joint !== null && b.idx < q.length) b.joint.setJointValue(q[b.idx]);
    }
    u.updateMatrixWorld(true);
  }

  jointNames() {
    return this.bound.map((b) => b.name);
  }

  /** The joints' values as the URDF robot holds them now (read back from urdf-loader's
   *  joints, not from a frame); null for a model joint the URDF lacks. */
  jointAngles() {
    return this.bound.map((b) => (b.joint === null ? null : b.joint.jointValue[0]));
  }

  /** World position of a URDF link (or any named frame), into `out`; false when unknown. */
  framePosition(name, out) {
    const f = this.urdf.frames[name] ?? this.urdf.links[name];
    if (!f) return false;
    f.getWorldPosition(out);
    return true;
  }

  basePosition(out) {
    return out.copy(this.urdf.position);
  }

  box() {
    return new THREE.Box3().setFromObject(this.urdf);
  }
}

function makeSkeleton(urdf) {
  const joints = Object.values(urdf.joints);
  const lengths = joints.map((j) => j.position.length()).filter((l) => l > 1e-6);
  const typical = lengths.length ? lengths.sort((a, b) => a - b)[lengths.length >> 1] : 0.1;
  const r = Math.max(0.004, 0.08 * typical);
  const material = new THREE.MeshPhongMaterial({ color: 0x56606b });
  const jointMaterial = new THREE.MeshPhongMaterial({ color: 0xe0892b });
  const parts = [];
  for (const j of joints) {
    const link = j.parent;
    if (!link) continue;
    const offset = j.position.clone();
    const len = offset.length();
    if (len > 1e-6) {
      const rod = new THREE.Mesh(new THREE.CylinderGeometry(0.5 * r, 0.5 * r, len, 12), material);
      rod.position.copy(offset).multiplyScalar(0.5);
      rod.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), offset.normalize());
      link.add(rod);
      parts.push(rod);
    }
    const ball = new THREE.Mesh(new THREE.SphereGeometry(r, 16, 12), jointMaterial);
    ball.position.copy(j.position);
    link.add(ball);
    parts.push(ball);
  }
  // A switch for all the parts (they live in the links).
  return {
    get visible() { return parts.length > 0 && parts[0].visible; },
    set visible(v) { for (const p of parts) p.visible = v; },
  };
}
