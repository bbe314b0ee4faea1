# Shared by the hour benchmarks (sourced, not run): `replay_runs BIN CONFIG
# RECORDING WORK RUNS` times `cat` of the recording, the whole-CLI replay
# and the replay in line (`--single-thread`) RUNS times, checks that the two
# replays write the same bytes and prints one line per run with the
# real-time factor of the one-hour recording.
seconds() { local t0 t1; t0=$(date +%s.%N); "$@" > /dev/null 2>&1; t1=$(date +%s.%N); echo "$t1 - $t0" | bc; }

replay_runs() {
  local bin=$1 config=$2 recording=$3 work=$4 runs=$5 run cat_s replay_s inline_s
  cat "$recording" > /dev/null # in the page cache, as for every run below
  echo "file: $(stat -c %s "$recording") bytes"
  for run in $(seq 1 "$runs"); do
    cat_s=$(seconds cat "$recording")
    replay_s=$(seconds "$bin" replay --config "$config" "$recording" --out "$work/results.mcap")
    inline_s=$(seconds "$bin" replay --config "$config" "$recording" --out "$work/results-in-line.mcap" --single-thread)
    cmp "$work/results.mcap" "$work/results-in-line.mcap"
    printf 'run %d: cat %.3f s; replay %.3f s (%.0fx real time); in line %.3f s (%.0fx)\n' \
      "$run" "$cat_s" "$replay_s" "$(echo "3600 / $replay_s" | bc -l)" "$inline_s" "$(echo "3600 / $inline_s" | bc -l)"
  done
}
