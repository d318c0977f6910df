#!/usr/bin/env python3
"""How far the rendering ETA was off: reads what `egogen-run` printed to a file (its plain progress
lines, `EGOGEN_PROGRESS_EVERY_S` apart) and prints, at 25, 50 and 75 % of the frames, the time
left it said against the time that was really left (the run's rendering seconds minus the
elapsed seconds of that line).

    EGOGEN_PROGRESS_EVERY_S=2 cargo run --release --locked --bin egogen-run -- \\
        configs/default.toml --out /tmp/eta_run 2> /tmp/eta_run.log
    python3 tools/eta_check.py /tmp/eta_run.log
"""
import re
import sys

LINE = re.compile(r"rendering (\d+)/(\d+) frames, (\d+) s elapsed, about (\d+) s left")
DONE = re.compile(r"rendered (\d+) frames in ([0-9.]+) s")


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: eta_check.py EGOGEN_RUN_STDERR.log")
    path = sys.argv[1]
    try:
        text = open(path, encoding="utf-8", errors="replace").read()
    except OSError as e:
        sys.exit(f"{path}: {e}")
    lines = [tuple(map(int, m.groups())) for m in LINE.finditer(text)]
    done = DONE.search(text)
    if not lines or not done:
        sys.exit(f"{path}: no progress lines with a time left, or no 'rendered N frames in S s' "
                 "line (set EGOGEN_PROGRESS_EVERY_S and keep standard error)")
    total_s = float(done.group(2))
    print("| frames done | elapsed s | said left s | really left s | error |")
    print("|---|---|---|---|---|")
    for share in (0.25, 0.5, 0.75):
        at = next(((pos, total, el, left) for pos, total, el, left in lines
                   if pos >= share * total), None)
        if at is None:
            continue
        pos, total, elapsed, said = at
        really = total_s - elapsed
        error = (said - really) / really if really > 0 else float("nan")
        print(f"| {pos}/{total} ({share:.0%}) | {elapsed} | {said} | {really:.0f} | {error:+.0%} |")


if __name__ == "__main__":
    main()
