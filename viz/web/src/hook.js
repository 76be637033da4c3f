// window.stride: the page's read-only hook for tests and scripts (viz/README.md).
//   ready       true once the robot is loaded and bound to the model, and (log mode) the log is
//               loaded and its first state shown; (live mode) once the model came
//   snapshot()  {t, joint_names, joint_angles, urdf_joint_count, frames_received, mode, base,
//               plan_t, planned_forces, force_scale, terrain, chosen_footholds}:
//               t the robot-clock stamp [s] of the state shown (null before any), joint_names
//               the model's actuated joints in wire order, joint_angles their values read back
//               from urdf-loader's joints (what is drawn), urdf_joint_count the movable joints
//               of the loaded URDF, frames_received the frames the page got (log mode: the
//               log's frames), mode 'live' or 'log', base the robot's root position as drawn
//               ([x, y, z] world, null before the robot), plan_t the stamp of the plan shown
//               (null when none), planned_forces its forces (per contact, [] when none),
//               force_scale the arrows' scale as the legend gives it (null before any force),
//               terrain the elevation map drawn (null when none): {t, rows, cols, resolution,
//               vertices (its known cells), triangles, bounds ([[x, y, z] min, [x, y, z] max]
//               of the mesh, null when no cell is known), visible}, chosen_footholds the rings
//               drawn at the plan's chosen footholds ([] when none): [{position (the ring's [x, y,
//               z] world, 3 mm above the foothold), contact, dt, source, color (hex number)}]
//   seek(t)     log mode: pauses and shows the log at t seconds from its start (clamped to
//               [0, duration()]): the newest state with stamp <= start + t; returns snapshot()
//   duration()  seconds from the first frame to the last (log mode), of the frames kept (live)
//   camera(v)   places the camera: looks at v.target from v.position ([x, y, z] world, m) and
//               draws; "follow", when on, moves it with the base from there. Without v, changes
//               nothing. Returns {target, position, fov (vertical, deg), aspect, width, height
//               (the 3D view in CSS pixels)}. For scripts that frame the robot themselves (the
//               paper's snapshot figures: tools/paper/snapshots.mjs)

export function installHook(viewer) {
  const hook = {
    snapshot: () => viewer.snapshot(),
    seek: (t) => {
      if (viewer.mode !== 'log' || viewer.player === null) return null;
      viewer.player.seek(Number(t));
      return viewer.snapshot();
    },
    camera: (view) => viewer.camera(view),
    duration: () => {
      if (viewer.player) return viewer.player.duration();
      const tracks = [viewer.states, viewer.plans, viewer.statuses].filter((tr) => tr.length > 0);
      if (tracks.length === 0) return 0;
      const first = Math.min(...tracks.map((tr) => tr.first().t));
      const last = Math.max(...tracks.map((tr) => tr.newest().t));
      return last - first;
    },
  };
  Object.defineProperty(hook, 'ready', { get: () => viewer.ready, enumerable: true });
  Object.freeze(hook);
  Object.defineProperty(window, 'stride', { value: hook, enumerable: true });
}
