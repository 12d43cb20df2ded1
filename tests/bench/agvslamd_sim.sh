# Sourced by the daemon benchmarks (daemon_latency.sh, soak.sh): the part of an agvslamd configuration that makes
# it run as on a vehicle on the simulator's camera (the shipped stage files, the detector one frame ahead of
# tracking, local mapping in its thread, base_link 0.5 m below the camera).
#   agvslamd_sim_pipeline_yaml SRC      prints the stages, pipeline and base_link sections; SRC: the source tree
agvslamd_sim_pipeline_yaml() {
  local src=$1
  cat <<EOF2
stages:
  features: $src/params/features.yaml
  slam: $src/params/slam.yaml
  dynamic: $src/params/dynamic.yaml
  stereo: $src/params/stereo.yaml
  place: $src/params/place.yaml
pipeline:
  dynamic: detector
  mapping: thread
base_link:
  z_m: 0.5
EOF2
}
