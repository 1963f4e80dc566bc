"""The tables of .ci/pil-figures, from the PIL's boot and scenario runs' JSON (and
flight-sitl's runs of the same scenarios) and the dist ELFs.

Usage: python3 .ci/pil_figures.py check|write RUNS_DIR
"""

import json
import re
import struct
import sys
from pathlib import Path

# The runners' scenario time starts this long after power-up (flight-sitl's WARMUP_S), s.
WARMUP_S = 4.0

# (run, image whose figures the row gives, which side of the run)
BOOT_ROWS = [
    ("brushedsparky", "flight-brushedsparky", "flight"),
    ("sparky2", "flight-sparky2", "flight"),
    ("brushedsparky-bl", "flight-brushedsparky-taulabs-bl", "flight"),
    ("sparky2-bl", "flight-sparky2-taulabs-bl", "flight"),
    ("brushedsparky", "module-nrf52840", "module"),
    ("uf2", "module-nrf52840-uf2", "module"),
]


def elf_symbols(path, names):
    """The values of the named symbols in a 32-bit little-endian ELF's symbol table."""
    data = Path(path).read_bytes()
    if data[:4] != b"\x7fELF" or data[4] != 1 or data[5] != 1:
        raise SystemExit(f"{path}: not a 32-bit little-endian ELF")
    shoff, = struct.unpack_from("<I", data, 0x20)
    shentsize, shnum = struct.unpack_from("<HH", data, 0x2E)
    sections = [struct.unpack_from("<IIIIIIIIII", data, shoff + i * shentsize) for i in range(shnum)]
    found = {}
    for sh in sections:
        if sh[1] != 2:  # SHT_SYMTAB
            continue
        strtab = sections[sh[6]]
        for off in range(sh[4], sh[4] + sh[5], 16):
            name_off, value = struct.unpack_from("<II", data, off)
            start = strtab[4] + name_off
            name = data[start:data.index(b"\0", start)].decode()
            if name in names:
                found[name] = value
    missing = set(names) - set(found)
    if missing:
        raise SystemExit(f"{path}: no symbol {', '.join(sorted(missing))}")
    return found


def thousands(n):
    return f"{n:,}".replace(",", " ")


def boot_table(runs):
    lines = [
        "| image | `boot_ms` (power-on → last task's first poll) | tasks polled / in the image "
        "| `max_stack_bytes` | `cpu_load_pct` (the whole 5 s run) | resets | first telemetry at "
        "the phone (after power-up; the phone connects at 3.4 s) | `boot` |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for run, image, side in BOOT_ROWS:
        report = runs[run]
        fig = report["images"][side]
        flight = side == "flight"
        first = report["pil"]["first_telemetry_s"]
        lines.append(
            f"| `{image}` | {fig['boot_ms']:.1f} | {fig['tasks_polled']} / {fig['tasks_in_image']} "
            f"| {thousands(fig['max_stack_bytes'])} | {fig['cpu_load_pct']:.1f} | {fig['resets']} "
            f"| {f'{first + WARMUP_S:.2f} s' if flight and first is not None else ''} "
            f"| {('met' if not report['criteria_failed'] else 'failed') if flight else ''} |"
        )
    return "\n".join(lines)


def stack_table(runs):
    lines = [
        "| image | stack room (`_stack_start` − `_stack_end`, flip-link: below the statics) "
        "| peak stack (PIL `boot`) | margin |",
        "|---|---|---|---|",
    ]
    for run, image, side in BOOT_ROWS:
        syms = elf_symbols(f"dist/{image}.elf", {"_stack_start", "_stack_end"})
        room = syms["_stack_start"] - syms["_stack_end"]
        peak = runs[run]["images"][side]["max_stack_bytes"]
        lines.append(
            f"| `{image}` | {thousands(room)} B | {thousands(peak)} B "
            f"| {thousands(room - peak)} B ({100 * (room - peak) / room:.0f} %) |"
        )
    return "\n".join(lines)


# (PIL scenario, its flight-sitl counterpart, why they pair) — the runs of .ci/pil-figures
SCENARIO_ROWS = [
    ("hover", "hover", "30 s both"),
    ("link-cut", "link-cut", "30 m"),
    ("imu-stall", "imu-stall", ""),
    ("i2c-stuck", "hover", "flight-sitl has no I²C: its hover of the same length"),
    ("settings-save", "power-cycle", "the PIL's phone also changes a setting"),
    ("panic", "panic", "PIL: a DMA transfer error; flight-sitl: the app's panic input"),
]


def num(value, digits=2, unit=""):
    return "–" if value is None else f"{value:.{digits}f}{unit}"


def pair(pil, sitl, key, digits=2):
    return f"{num(pil.get(key), digits)} · {num(sitl.get(key), digits)}"


def verdict(report, rc):
    failed = report.get("criteria_failed")
    if failed is None:
        return "met" if rc == 0 else "failed"
    return "met" if not failed else "failed: " + "; ".join(failed)


def scenario_table(pil_runs, sitl_runs):
    lines = [
        "| PIL scenario · flight-sitl's | criteria (PIL · flight-sitl) | max altitude, m "
        "| failsafe at, s | disarmed at, s (reason) | touchdown, m/s "
        "| reset in the air: motors off after · for, s; link's word after, s; sank, m "
        "| flight watchdog resets |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for pil_name, sitl_name, note in SCENARIO_ROWS:
        p, prc = pil_runs[pil_name]
        s, src = sitl_runs[pil_name]
        disarm = " · ".join(
            f"{num(r.get('disarmed_at_s'))} ({r.get('disarm_reason') or '–'})" for r in (p, s)
        )
        if "resumed" in s:
            resume = " · ".join(
                f"{num(r.get('motors_off_after_s'), 3)}, {num(r.get('motors_off_for_s'), 3)}; "
                f"{num(r.get('link_word_after_s'), 3)}; {num(r.get('drop_m'))}"
                for r in (p, s)
            )
        else:
            resume = ""
        lines.append(
            f"| `{pil_name}` · `{sitl_name}`{f' ({note})' if note else ''} "
            f"| {verdict(p, prc)} · {verdict(s, src)} | {pair(p, s, 'max_altitude_m')} "
            f"| {pair(p, s, 'failsafe_at_s')} | {disarm} | {pair(p, s, 'touchdown_speed_mps')} "
            f"| {resume} | {p['watchdog_resets']['flight']} · {s['watchdog_resets']['flight']} |"
        )
    return "\n".join(lines)


def read_run(path):
    try:
        report = json.loads(path.read_text())
        rc = int(path.with_suffix(".rc").read_text().strip() or 1)
    except (OSError, ValueError) as e:
        raise SystemExit(f"{path}: no report to read ({e})")
    return report, rc


def replace_block(path, name, body, mode):
    text = Path(path).read_text()
    pattern = re.compile(
        rf"(<!-- {name}: generated by \.ci/pil-figures -->\n)(.*?)(<!-- end {name} -->)", re.S
    )
    match = pattern.search(text)
    if match is None:
        raise SystemExit(f"{path}: no `{name}` block (<!-- {name}: generated by .ci/pil-figures -->)")
    if match.group(2) == body + "\n":
        return True
    if mode == "write":
        Path(path).write_text(text[: match.start(2)] + body + "\n" + text[match.end(2):])
        print(f"{path}: `{name}` rewritten")
        return True
    print(f"{path}: `{name}` differs from the fresh runs (.ci/pil-figures write):\n{body}")
    return False


def main():
    if len(sys.argv) != 3 or sys.argv[1] not in ("check", "write"):
        raise SystemExit("usage: pil_figures.py check|write RUNS_DIR")
    mode, runs_dir = sys.argv[1], Path(sys.argv[2])
    runs = {}
    for run, _, _ in BOOT_ROWS:
        path = runs_dir / f"{run}.json"
        try:
            runs[run] = json.loads(path.read_text())
        except (OSError, ValueError) as e:
            raise SystemExit(f"{path}: no boot report to read ({e})")
    pil_runs = {name: read_run(runs_dir / f"pil-{name}.json") for name, _, _ in SCENARIO_ROWS}
    sitl_runs = {name: read_run(runs_dir / f"sitl-{name}.json") for name, _, _ in SCENARIO_ROWS}
    failed = [name for name, (_, rc) in pil_runs.items() if rc != 0]
    ok = replace_block("tests/pil/README.md", "pil-boot", boot_table(runs), mode)
    ok = replace_block(
        "tests/pil/README.md", "pil-scenarios", scenario_table(pil_runs, sitl_runs), mode
    ) and ok
    ok = replace_block("README.md", "pil-stack", stack_table(runs), mode) and ok
    if failed:
        print(f"PIL scenarios with unmet criteria: {', '.join(failed)}")
    sys.exit(0 if ok and not failed else 1)


if __name__ == "__main__":
    main()
