# Sourced by the pmg_teleop_bench tests: expect_refused BIN TASK DIR NAME CONTENT PATTERN...
# writes CONTENT to DIR/NAME.yaml, runs one trial of TASK with it as the operator file, and fails
# (exit 1, printing the output) unless the run is refused and its message matches every PATTERN
# (grep regular expressions: the file, the field, the expected range).
expect_refused() {
  local bin="$1" task="$2" dir="$3" name="$4" content="$5"
  shift 5
  printf '%b' "$content" > "$dir/$name.yaml"
  if "$bin/pmg_teleop_bench" --task "$task" --trials 1 --operator "$dir/$name.yaml" --out "$dir/$name" > "$dir/$name.txt" 2>&1; then
    echo "FAIL: $task operator file $name.yaml ($content) was accepted"; exit 1
  fi
  local p
  for p in "$@"; do
    grep -q -- "$p" "$dir/$name.txt" || { echo "FAIL: $name: the refusal does not say '$p':"; cat "$dir/$name.txt"; exit 1; }
  done
}
