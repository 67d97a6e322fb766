# Sourced by scripts that run a mapping graph (soak.sh, robot_budget.sh): start_mapping_graph
# LAUNCH_FILE LOG [roslaunch arguments...] starts a ROS master on a free port with the launch
# file, stops both when the script exits (and a process whose pid the script put into $player),
# and returns once the MapServer serves ~save_map and the mappers loaded after it had 3 s to
# subscribe. Needs the build's devel/setup.bash sourced.
start_mapping_graph() {
  local launch_file="$1" log="$2"
  shift 2
  export ROS_HOSTNAME=localhost
  local port
  port="$(python3 -c 'import socket; s=socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])')"
  export ROS_MASTER_URI="http://localhost:$port"
  roslaunch -p "$port" "$launch_file" "$@" > "$log" 2>&1 &
  launch=$!
  trap stop_mapping_graph EXIT
  timeout 120 python3 -c '
import time, rosgraph
master = rosgraph.Master("/mapping_graph")
while True:
    try:
        master.lookupService("/map_server/save_map")
        break
    except Exception:  # master not up yet, or service not advertised yet
        time.sleep(1)'
  sleep 3  # the mappers' subscriptions and tf listeners, loaded after the map server
}

stop_mapping_graph() {
  [[ -n "${player:-}" ]] && kill -INT "$player" 2> /dev/null || true
  kill -INT "$launch" 2> /dev/null || true
  wait "$launch" 2> /dev/null || true
}
