# Sourced by the device prep scripts under docs/bench/logs-*: `executables` reads cargo's
# `--message-format=json` on stdin and prints "TARGET EXECUTABLE" for each program built.
executables() {
  python3 -c "import sys, json
for l in sys.stdin:
    d = json.loads(l)
    if d.get('reason') == 'compiler-artifact' and d.get('executable'):
        print(d['target']['name'], d['executable'])"
}
