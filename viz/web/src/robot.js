// The robot: its URDF drawn by urdf-loader (visual geometry: boxes, cylinders, spheres, and meshes
// when their files load), posed from a configuration q in wire order (controller/README.md,
// "Wire contract"): q[0:3] base position, q[3:7] base quaternion x y z w for a floating base, then
// each joint's coordinate at the model's idx_q, set on the URDF joint of the same name.

import * as THREE from 'three';
import URDFLoader from 'urdf-loader';
import { STLLoader } from 'three/addons/loaders/STLLoader.js';
import { ColladaLoader } from 'three/addons/loaders/ColladaLoader.js';
import { OBJLoader } from 'three/addons/loaders/OBJLoader.js';

/**
 * Loads the URDF at `url`. Meshes load in the background; one that fails (missing, unknown
 * format) is reported through `onWarning` and the robot is drawn without it.
 */
export function loadRobot(url, onWarning) {
  const manager = new THREE.LoadingManager();
  const loader = new URDFLoader(manager);
  loader.parseVisual = true;
  loader.parseCollision = false;
  loader.loadMeshCb = (path, mgr, material, done) => {
    const failed = (why) => {
      onWarning(`mesh ${path.split('/').pop()} not shown: ${why}`);
      done(null); // no error object: the robot stays, without this mesh
    };
    const ext = (path.match(/\.([a-z0-9]+)$/i)?.[1] ?? '').toLowerCase();
    const onError = (e) => failed(e?.message ?? 'not found');
    if (ext === 'stl') {
      new STLLoader(mgr).load(path, (geometry) => {
        geometry.computeVertexNormals();
        done(new THREE.Mesh(geometry, material));
      }, undefined, onError);
    } else if (ext === 'dae') {
      new ColladaLoader(mgr).load(path, (dae) => done(dae.scene), undefined, onError);
    } else if (ext === 'obj') {
      new OBJLoader(mgr).load(path, (obj) => {
        obj.traverse((c) => { if (c.isMesh) c.material = material; });
        done(obj);
      }, undefined, onError);
    } else {
      failed(`no loader for .${ext}`);
    }
  };
  return new Promise((resolve, reject) => {
    loader.load(url, (urdf) => resolve(new RobotView(urdf)), undefined,
                (e) => reject(new Error(`the robot's URDF (${url}): ${e?.message ?? e}`)));
  });
}

export class RobotView {
  constructor(urdf) {
    this.urdf = urdf;
    // URDF colours are written as sRGB; three's materials take linear values.
    urdf.traverse((c) => {
      if (c.isMesh && c.material && c.material.color && !c.material.userData.strideLinear) {
        c.material.color.convertSRGBToLinear();
        c.material.userData.strideLinear = true;
      }
    });
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
