#!/usr/bin/env python3
"""Summarises the `link` bench's m4count output (five regions per slot, see src/bin/link.rs):
per slot kind, the master's and the follower's instructions (min, mean, max).

usage: ../shared/tools/m4count/m4count target/thumbv7em-none-eabihf/release/link \\
           | python3 tests/m4-bench/link_summary.py
"""
import statistics
import sys

regions = [int(l.split()[2]) for l in sys.stdin if l.startswith("region")]
slots = [regions[i:i + 5] for i in range(0, len(regions) - len(regions) % 5, 5)]
# An uplink slot is one where the master builds a frame (its plan is the long region).
kinds = {"uplink": [s for s in slots if s[0] > s[1]], "downlink": [s for s in slots if s[0] <= s[1]]}
parts = [("master plan", [0]), ("master completion", [2]), ("master per slot", [0, 2]),
         ("follower plan", [1]), ("follower completion", [3]), ("follower per slot", [1, 3])]
for kind, ss in kinds.items():
    for label, idx in parts:
        v = [sum(s[i] for i in idx) for s in ss]
        if v:
            print(f"{kind:8} {label:20} n={len(v):3} min={min(v):5} "
                  f"mean={statistics.mean(v):7.0f} max={max(v):5}")
