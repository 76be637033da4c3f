#!/usr/bin/env bash
# stride-init (issue 34, "Bring your own robot"): HyQ and Solo-12 from their URDF and SRDF (the
# package view of ../shared/robots) are set up, load in stride-mpc --print-model, and track their
# drive (exit 0); refusals: placeholder efforts without --torque-limit, an existing file without
# --force, a bad --sole-half-extents (exit 2, each with its message); Bolt (a point-foot biped) with
# its posture corrected.
# Also ANYmal C, talos_reduced and the full TALOS (its 12 gripper <mimic> joints: the two leaders
# locked) are set up and tracked.
# Usage: init_robots.sh checks|drives STRIDE_INIT STRIDE_MPC ROBOT_PACKAGES
#   checks: the refusals and every robot's files with --no-drive (loaded by stride-mpc): fast,
#           under the sanitizers too; drives: every robot set up and driven (ctest init_robots_drives,
#           label sanitize_slow: the drives' paths are ClosedLoop.*'s).
set -uo pipefail
mode=$1 init=$2 mpc=$3 packages=$4
p=package://example-robot-data/robots
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAILED: $*"; exit 1; }
run() {  # expected-status output-file args...
  local want=$1 out=$2 status=0
  shift 2
  "$init" "$@" > "$out" 2>&1 || status=$?
  [ "$status" = "$want" ] || { cat "$out"; fail "stride-init $* exited $status, not $want"; }
}
loads() {  # controller YAML
  "$mpc" --config "$1" --robots-dir "$packages" --print-model > "$work/model.txt" 2>&1 ||
    { cat "$work/model.txt"; fail "stride-mpc --print-model refused $1"; }
}

# Refusals first (fast).
solo=(--urdf "$p/solo_description/robots/solo12.urdf" --srdf "$p/solo_description/srdf/solo.srdf"
      --robots-dir "$packages")
run 2 "$work/placeholder.txt" "${solo[@]}" --out "$work/solo12" --no-drive
grep -q "placeholder" "$work/placeholder.txt" && grep -q -- "--torque-limit" "$work/placeholder.txt" &&
  grep -q "FL_HFE" "$work/placeholder.txt" || { cat "$work/placeholder.txt"; fail "placeholder message"; }
[ ! -e "$work/solo12" ] || fail "files written despite the refusal"
echo "ok: placeholder efforts refused"

# A tiny 2 kg URDF of our own with effort 1000.
mkdir -p "$work/tiny"
cat > "$work/tiny/tiny.urdf" <<'EOF'
<robot name="tiny">
  <link name="base"><inertial><mass value="1.0"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="left_leg"><inertial><origin xyz="0 0 -0.1"/><mass value="0.5"/><inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 -0.2"/><geometry><sphere radius="0.01"/></geometry></collision></link>
  <link name="right_leg"><inertial><origin xyz="0 0 -0.1"/><mass value="0.5"/><inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 -0.2"/><geometry><sphere radius="0.01"/></geometry></collision></link>
  <link name="left_foot"/><link name="right_foot"/>
  <joint name="left_hip" type="revolute"><parent link="base"/><child link="left_leg"/><origin xyz="0 0.1 0"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1000" velocity="10"/></joint>
  <joint name="right_hip" type="revolute"><parent link="base"/><child link="right_leg"/><origin xyz="0 -0.1 0"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1000" velocity="10"/></joint>
  <joint name="left_ankle" type="fixed"><parent link="left_leg"/><child link="left_foot"/><origin xyz="0 0 -0.2"/></joint>
  <joint name="right_ankle" type="fixed"><parent link="right_leg"/><child link="right_foot"/><origin xyz="0 0 -0.2"/></joint>
</robot>
EOF
cat > "$work/tiny/tiny.srdf" <<'EOF'
<robot name="tiny">
  <end_effector name="r" parent_link="right_foot" group="r"/>
  <end_effector name="l" parent_link="left_foot" group="l"/>
  <group_state name="standing" group="all"><joint name="left_hip" value="0"/><joint name="right_hip" value="0"/></group_state>
</robot>
EOF
run 2 "$work/tiny.txt" --urdf "$work/tiny/tiny.urdf" --srdf "$work/tiny/tiny.srdf" --out "$work/tiny_out" --no-drive
grep -q "placeholder (1000 N m on a 2.00 kg robot)" "$work/tiny.txt" && grep -q "left_hip, right_hip" "$work/tiny.txt" ||
  { cat "$work/tiny.txt"; fail "the tiny robot's placeholder message"; }
# With a limit it is set up, its feet left then right whatever the SRDF's order.
run 0 "$work/tiny.txt" --urdf "$work/tiny/tiny.urdf" --srdf "$work/tiny/tiny.srdf" --torque-limit 5 \
  --out "$work/tiny_out" --no-drive
grep -A2 "^contacts:" "$work/tiny_out/tiny.yaml" | tail -2 | grep -o "frame: [a-z_]*" | tr '\n' ' ' |
  grep -q "frame: left_foot frame: right_foot" || { cat "$work/tiny_out/tiny.yaml"; fail "tiny's foot order"; }
echo "ok: a 2 kg robot with effort 1000 refused, set up with --torque-limit"

# An existing file is not overwritten without --force.
run 2 "$work/exists.txt" --urdf "$work/tiny/tiny.urdf" --srdf "$work/tiny/tiny.srdf" --torque-limit 5 \
  --out "$work/tiny_out" --no-drive
grep -q "exists: not overwritten (pass --force" "$work/exists.txt" || { cat "$work/exists.txt"; fail "exists message"; }
run 0 "$work/exists.txt" --urdf "$work/tiny/tiny.urdf" --srdf "$work/tiny/tiny.srdf" --torque-limit 5 \
  --out "$work/tiny_out" --no-drive --force
run 2 "$work/sole.txt" --urdf "$work/tiny/tiny.urdf" --srdf "$work/tiny/tiny.srdf" --torque-limit 5 \
  --out "$work/tiny_out2" --no-drive --sole-half-extents 0.1
grep -q "expected X,Y" "$work/sole.txt" || { cat "$work/sole.txt"; fail "sole message"; }
echo "ok: an existing file kept without --force, replaced with it; a bad --sole-half-extents refused"

if [ "$mode" = checks ]; then
  # Every robot's files without the drive: written, loaded by stride-mpc.
  tal=(--urdf "$p/talos_data/robots/talos_full_v2.urdf" --srdf "$p/talos_data/srdf/talos.srdf"
       --robots-dir "$packages" --sole-half-extents 0.1,0.065 --name talos_full)
  run 0 "$work/talos_full.txt" "${tal[@]}" --out "$work/talos_full" --no-drive
  grep -q "joint 'gripper_left_joint' locked at 0 (its <mimic> joints follow it" "$work/talos_full.txt" ||
    { cat "$work/talos_full.txt"; fail "the full TALOS's gripper leaders are not said locked"; }
  grep -A2 "^locked_joints:" "$work/talos_full/talos_full.yaml" | grep -q "gripper_right_joint: 0" ||
    { cat "$work/talos_full/talos_full.yaml"; fail "no locked_joints in the full TALOS's YAML"; }
  loads "$work/talos_full/talos_full_controller.yaml"
  grep -q "nq 37, nv 36, nu 30" "$work/model.txt" || { cat "$work/model.txt"; fail "full TALOS's sizes"; }
  # Unlocking a gripper by hand is refused by the URDF loader, naming a mimic joint.
  run 2 "$work/talos_bad.txt" "${tal[@]}" --out "$work/talos_bad" --no-drive --lock head_1_joint=0.0 \
    --lock gripper_left_inner_double_joint=0.0 --lock gripper_left_joint=0.5
  grep -q "gripper_left" "$work/talos_bad.txt" || { cat "$work/talos_bad.txt"; fail "a locked mimic disagreeing with its leader"; }
  run 0 "$work/solo12.txt" "${solo[@]}" --name solo12 --torque-limit 2.7 --out "$work/solo12" --no-drive
  loads "$work/solo12/solo12_controller.yaml"
  echo "ok: the full TALOS with its grippers locked (nv 36, 30 motors), solo12: files written and loaded"
  exit 0
fi

# Solo-12 and HyQ: set up, loaded by stride-mpc, driven: every segment tracked, the push survived.
run 0 "$work/solo12.txt" "${solo[@]}" --name solo12 --torque-limit 2.7 --out "$work/solo12"
cat "$work/solo12.txt"
loads "$work/solo12/solo12_controller.yaml"
grep -q "push .*survived" "$work/solo12.txt" || fail "solo12's push"
run 0 "$work/hyq.txt" --urdf "$p/hyq_description/robots/hyq_no_sensors.urdf" \
  --srdf "$p/hyq_description/srdf/hyq.srdf" --robots-dir "$packages" --name hyq --out "$work/hyq"
cat "$work/hyq.txt"
loads "$work/hyq/hyq_controller.yaml"
grep -q "template anymal_c" "$work/hyq.txt" || fail "HyQ's template (87 kg: anymal_c)"
echo "ok: solo12 and hyq tracked"

# Bolt: a point-foot biped whose SRDF standing has its centre of mass 1.9 cm behind the feet: the
# hip pitches corrected (the numbers printed), written as default_posture joints, and it tracks.
run 0 "$work/bolt.txt" --urdf "$p/bolt_description/robots/bolt.urdf" \
  --srdf "$p/bolt_description/srdf/bolt.srdf" --robots-dir "$packages" --name bolt \
  --torque-limit 2.7 --out "$work/bolt"
cat "$work/bolt.txt"
grep -q "1.9 cm behind the feet's line; turned FL_HFE and FR_HFE" "$work/bolt.txt" ||
  fail "Bolt's posture correction"
grep -q "FL_HFE: 0.86" "$work/bolt/bolt.yaml" || fail "Bolt's corrected hip pitch in its YAML"
loads "$work/bolt/bolt_controller.yaml"
echo "ok: bolt corrected and tracked"
# ANYmal C, talos_reduced and the full TALOS: set up as the shipped ones are, and tracked.
run 0 "$work/anymal_c.txt" --urdf "$p/anymal_c_simple_description/urdf/anymal.urdf" \
  --srdf "$p/anymal_c_simple_description/srdf/anymal.srdf" --robots-dir "$packages" --name anymal_c \
  --out "$work/anymal_c"
cat "$work/anymal_c.txt"
run 0 "$work/talos_reduced.txt" --urdf "$p/talos_data/robots/talos_reduced.urdf" \
  --srdf "$p/talos_data/srdf/talos.srdf" --robots-dir "$packages" --name talos_reduced \
  --sole-half-extents 0.1,0.065 --out "$work/talos_reduced"
cat "$work/talos_reduced.txt"
run 0 "$work/talos_full.txt" --urdf "$p/talos_data/robots/talos_full_v2.urdf" \
  --srdf "$p/talos_data/srdf/talos.srdf" --robots-dir "$packages" --name talos_full \
  --sole-half-extents 0.1,0.065 --out "$work/talos_full"
cat "$work/talos_full.txt"
echo "ok: anymal_c, talos_reduced and the full TALOS tracked"
