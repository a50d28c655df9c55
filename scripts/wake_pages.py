#!/usr/bin/env python3
"""What one wake-up of an agent touches, from valgrind lackey's trace
(`--trace-mem=yes`) of that agent: the trace is cut at each entry of the
doorbell's futex wait (one wake-up runs from there to the next), and each
wake-up's distinct 64-byte lines and 4 KiB pages of code and of data are
counted. Prints the medians over the wake-ups that answered a snapshot.

    wake_pages.py SPLIT_ADDRESS_HEX < lackey-trace
"""
import statistics
import sys


def main():
    split = int(sys.argv[1], 16)
    code_lines, code_pages, data_lines, data_pages = set(), set(), set(), set()
    instructions = 0
    wakeups = []
    for line in sys.stdin:
        if line.startswith("I  "):
            a, _, size = line[3:].partition(",")
            a = int(a, 16)
            if a == split:
                if instructions:
                    wakeups.append((instructions, len(code_lines), len(code_pages),
                                    len(data_lines), len(data_pages)))
                for s in (code_lines, code_pages, data_lines, data_pages):
                    s.clear()
                instructions = 0
            instructions += 1
            e = a + int(size) - 1
            code_lines.update((a >> 6, e >> 6))
            code_pages.update((a >> 12, e >> 12))
        elif len(line) > 3 and line[0] == " " and line[1] in "LSM":
            a, _, size = line[3:].partition(",")
            a = int(a, 16)
            e = a + int(size) - 1
            data_lines.update((a >> 6, e >> 6))
            data_pages.update((a >> 12, e >> 12))
    # The first two are the join's; a wake-up without a snapshot runs a
    # few hundred instructions, one after a stall far more.
    rows = [w for w in wakeups[2:] if 2000 < w[0] < 100000]
    if not rows:
        sys.exit("no wake-up with a snapshot in the trace")
    med = [statistics.median(w[k] for w in rows) for k in range(5)]
    print(f"{len(rows)} wake-ups, medians: {med[0]:.0f} instructions; "
          f"code {med[1]:.0f} lines on {med[2]:.0f} pages; "
          f"data {med[3]:.0f} lines on {med[4]:.0f} pages")


main()
