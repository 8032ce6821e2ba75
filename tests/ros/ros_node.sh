#!/usr/bin/env bash
# ros_node: multislit_ros in a ROS 1 graph on loopback only (ROS_MASTER_URI and ROS_IP on
# 127.0.0.1, a free port, ROS_HOME and the logs in the work dir).
#  1. roscore, waited for until its master answers.
#  2. The launch file runs the node on the simulated ping-pong ball (poses from TF, which
#     ros_node_test publishes as the robot would) while `rosbag record` records every topic;
#     ros_node_test checks the messages, and against `multislit map` on the same 30 frames.
#  3. The program alone on the tennis ball and box of Fig. 8, poses from nav_msgs/Odometry of a
#     robot standing at (1.0, 0.5) facing +y: the map holds the objects where that robot sees
#     them; a picture of the last frame as a viewer shows it (ros_view.png).
#  4. rosbag info reads the bag of 2: every topic with its messages.
# Run as: bash ros_node.sh <multislit> <ros_node_test> <package dir of multislit_ros> <work dir>
set -u
multislit=$1
checker=$2
package=$3
work=$4
source "$(dirname "${BASH_SOURCE[0]}")/../check_support.sh"
rm -rf "$work" && mkdir -p "$work"
[[ -x $package/multislit_ros ]] || fail "no multislit_ros in $package"

# ROS 1's tools are programs of Debian's Python: its python3 first, not one of pyenv or a venv.
export PATH=/usr/bin:$PATH
unset ROS_HOSTNAME ROS_NAMESPACE
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://127.0.0.1:$port ROS_IP=127.0.0.1
export ROS_HOME=$work/ros_home ROS_LOG_DIR=$work/log ROS_PACKAGE_PATH=$(dirname "$package")
now() { date +%s.%N; }
since() { python3 -c "print(f'{$(now) - $1:.1f} s')"; }
t_start=$(now)

pids=()
# stop PID: SIGINT (the ROS tools close their files on it), then SIGKILL after 20 s; returns the
# exit code.
stop() {
  local pid=$1 i
  kill -INT "$pid" 2>/dev/null
  for ((i = 0; i < 200; i++)); do
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  kill -KILL "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null
}
cleanup() {
  local i
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do stop "${pids[i]}"; done
}
trap cleanup EXIT

# `multislit map` on the same 30 frames of the ball, for comparison.
"$multislit" map --simulate ball --frames 30 --out "$work/map" >"$work/map.log" 2>&1 ||
  fail "multislit map: $(tail -3 "$work/map.log")"

# 1. The master, up when it answers getSystemState (60 s at most).
roscore -p "$port" >"$work/roscore.log" 2>&1 &
pids+=($!)
python3 - "$port" <<'EOF' || fail "roscore did not answer on 127.0.0.1:$port: $(tail -5 "$work/roscore.log")"
import sys, time, xmlrpc.client
master = xmlrpc.client.ServerProxy(f"http://127.0.0.1:{sys.argv[1]}")
deadline = time.monotonic() + 60
while time.monotonic() < deadline:
    try:
        if master.getSystemState("/ros_node_test")[0] == 1:
            sys.exit(0)
    except OSError:
        pass
    time.sleep(0.05)
sys.exit(1)
EOF
echo "roscore on 127.0.0.1:$port after $(since "$t_start")"

# checked_run NAME CHECKER_ARGS... -- NODE_COMMAND...: the node command and ros_node_test with
# the arguments side by side, logs NAME_check.log and NAME_node.log; fails unless the checks
# pass, then stops the node.
checked_run() {
  local name=$1 args=() node rc t0
  shift
  while [[ $1 != -- ]]; do
    args+=("$1")
    shift
  done
  shift
  t0=$(now)
  "$checker" "${args[@]}" >"$work/${name}_check.log" 2>&1 &
  local check=$!
  "$@" >"$work/${name}_node.log" 2>&1 &
  node=$!
  pids+=($node)
  wait $check
  rc=$?
  cat "$work/${name}_check.log"
  ((rc == 0)) || fail "ros_node_test on $name (rc $rc); the node said: $(tail -20 "$work/${name}_node.log")"
  [[ -z ${after_check:-} ]] || $after_check
  # Shut down (Ctrl-C), the node ends cleanly: rc 0 and, under ASan, no leak.
  stop $node
  rc=$?
  ((rc == 0)) || fail "$name: the node's command ended with rc $rc: $(tail -20 "$work/${name}_node.log")"
  ! grep -q "process has died" "$work/${name}_node.log" ||
    fail "$name: the node died: $(grep "process has died" "$work/${name}_node.log")"
  echo "$name: $(since "$t0")"
}

# ~pose_timeout 1 s in both runs: on 2 cores shared with other tests (ctest -j2, the sanitizers)
# a pose can come more than the default 0.1 s after the frame it is for.

# 2. The launch file, TF poses, a bag.
topics=(/multislit/rdmap /multislit/floor /multislit/obstacles /multislit/obstacle_markers
  /multislit/octomap_binary /multislit/octomap_full /multislit/projected_map
  /multislit/octomap_point_cloud_centers /multislit/decision /diagnostics /tf /tf_static)
rosbag record -O "$work/run.bag" "${topics[@]}" >"$work/rosbag.log" 2>&1 &
bag=$!
pids+=($bag)
checked_run ball --scenario ball --frames 30 --poses tf --node-out "$work/node_ball" \
  --map-out "$work/map" -- roslaunch multislit_ros multislit.launch simulate:=ball frames:=30 \
  poses:=tf pose_timeout:=1.0 out:="$work/node_ball" wait_for_subscribers:=2 resolution:=0.01
stop $bag

# rospy reads the node's messages (genpy's modules in the package's python/): rostopic echo prints
# the latched floor and decision of the last frame.
echo_messages() {
  local topic
  for topic in floor decision; do
    PYTHONPATH=$package/python${PYTHONPATH:+:$PYTHONPATH} timeout 120 rostopic echo -n 1 \
      "/multislit/$topic" >"$work/echo_$topic.txt" 2>&1 ||
      fail "rostopic echo /multislit/$topic: $(tail -3 "$work/echo_$topic.txt")"
  done
  grep -q '^  frame_id: "multislit_optical"' "$work/echo_floor.txt" &&
    grep -q "^found: True" "$work/echo_floor.txt" &&
    grep -q "^valid_points: [1-9]" "$work/echo_floor.txt" ||
    fail "rostopic echo /multislit/floor: $(cat "$work/echo_floor.txt")"
  grep -q '^  frame_id: "base_footprint"' "$work/echo_decision.txt" &&
    grep -qE '^command_name: "(walk|turn|stop)"' "$work/echo_decision.txt" ||
    fail "rostopic echo /multislit/decision: $(cat "$work/echo_decision.txt")"
  echo "rostopic echo: the floor and the decision of the last frame"
}

# 3. The program alone: odometry poses, the map's parameters, the picture.
after_check=echo_messages checked_run fig8 --scenario fig8 --frames 8 --poses odom \
  --robot 1.0,0.5,90 --resolution 0.02 --figure "$work/ros_view.png" -- \
  "$package/multislit_ros" _simulate:=fig8 _frames:=8 _poses:=odom _pose_timeout:=1.0 \
  _wait_for_subscribers:=1 _resolution:=0.02 _sensor_model/hit:=0.9 _sensor_model/miss:=0.45 \
  _sensor_model/min:=0.1 _sensor_model/max:=0.95 _pointcloud_max_z:=0.25
[[ -s $work/ros_view.png ]] || fail "no picture"
grep -q "unknown parameter" "$work/fig8_node.log" &&
  fail "fig8: octomap_server's parameters were not known: $(grep "unknown parameter" "$work/fig8_node.log")"

# 4. The robot publishes the camera mount on TF, 0.3 m further forward than the sensor's: the node
# takes it (the picture above keeps the sensor's).
checked_run mount --scenario fig8 --frames 8 --poses odom --robot 1.0,0.5,90 --resolution 0.02 \
  --mount-shift 0.3 -- "$package/multislit_ros" _simulate:=fig8 _frames:=8 _poses:=odom \
  _pose_timeout:=1.0 _wait_for_subscribers:=1 _resolution:=0.02 _publish_mount_tf:=false
# octomap_server's parameters are checked by OccupancyMapConfig::validate(), named (the last run:
# the parameter stays on the server).
"$package/multislit_ros" _simulate:=fig8 _sensor_model/hit:=0.3 >"$work/bad_param.log" 2>&1 &&
  fail "~sensor_model/hit 0.3 was taken"
grep -q "~sensor_model/hit: OccupancyMapConfig.prob_hit must be in (0.5, 1)" "$work/bad_param.log" ||
  fail "~sensor_model/hit 0.3: $(tail -3 "$work/bad_param.log")"

# 5. The bag.
rosbag info "$work/run.bag" >"$work/bag_info.txt" 2>&1 || fail "rosbag info: $(cat "$work/bag_info.txt")"
cat "$work/bag_info.txt"
for topic in "${topics[@]}"; do
  count=$(awk -v t="$topic" '{ for (i = 1; i < NF; i++) if ($i == t) print $(i + 1) }' \
    "$work/bag_info.txt" | head -1)
  [[ -n $count && $count -gt 0 ]] || fail "the bag has no $topic"
done
grep -q "/multislit/rdmap  *30 msgs" "$work/bag_info.txt" || fail "the bag has not the 30 clouds"
grep -q "octomap_msgs/Octomap  *\[9a45536b45c5e409cd49f04bb2d9999f\]" "$work/bag_info.txt" ||
  fail "the bag's octomap_msgs/Octomap is not upstream's"
# 6. The package's rviz view shows only topics the node published (the bag holds them).
/usr/bin/python3 - "$package/rviz/multislit.rviz" "$work/bag_info.txt" <<'EOF' || fail "rviz/multislit.rviz"
import sys, yaml
config = yaml.safe_load(open(sys.argv[1]))
manager = config["Visualization Manager"]
assert manager["Global Options"]["Fixed Frame"] == "base_footprint", "fixed frame"
topics = [d.get("Topic") or d.get("Marker Topic") for d in manager["Displays"]]
topics = [t for t in topics if t]
recorded = open(sys.argv[2]).read().split()
missing = [t for t in topics if t not in recorded]
assert len(topics) == 4 and not missing, f"topics {topics}, not published: {missing}"
print(f"rviz/multislit.rviz: fixed frame base_footprint, {len(topics)} topics, all published")
EOF
echo "ros_node: all checks passed in $(since "$t_start")"
