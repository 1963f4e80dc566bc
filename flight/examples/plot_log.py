#!/usr/bin/env python3
"""A TauLink flight log (ULog) drawn with pyulog and matplotlib: the estimate against the
raw sensors it came from, and the identified airframe (β per axis, the motor τ).

    pip install pyulog matplotlib
    python plot_log.py FLIGHT.ulg --out DIR

Writes DIR/attitude.png (roll and pitch estimated, and from the accelerometer alone; the
gyro's rates), DIR/altitude.png (the estimate's altitude and climb against the baro) and,
when the log holds an identification flight, DIR/identification.png (β and τ as the
identification converged, its final values in the title). A log from the simulator:
`cargo run --release -p flight-sitl -- hover --gps --log hover.ulg`."""

import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from pyulog import ULog  # noqa: E402


def topic(log, name):
    """The topic's fields as arrays, time in seconds, or None when it was not logged."""
    for d in log.data_list:
        if d.name == name:
            data = dict(d.data)
            data["t"] = data["timestamp"] * 1e-6
            return data
    return None


def attitude(imu, est, out):
    fig, (ang, rate) = plt.subplots(2, 1, sharex=True, figsize=(10, 6))
    if est is not None:
        ang.plot(est["t"], est["euler_deg[0]"], label="roll, estimate")
        ang.plot(est["t"], est["euler_deg[1]"], label="pitch, estimate")
    if imu is not None:
        # Body FRD specific force: at rest it points up, (0, 0, -g).
        ax, ay, az = imu["accel_mps2[0]"], imu["accel_mps2[1]"], imu["accel_mps2[2]"]
        ang.plot(imu["t"], np.degrees(np.arctan2(-ay, -az)), ".", ms=2, label="roll, accelerometer")
        ang.plot(imu["t"], np.degrees(np.arctan2(ax, np.hypot(ay, az))), ".", ms=2,
                 label="pitch, accelerometer")
        for i, axis in enumerate("pqr"):
            rate.plot(imu["t"], np.degrees(imu[f"gyro_radps[{i}]"]), label=f"{axis}, gyro")
    ang.set_ylabel("deg")
    ang.legend(loc="upper right", fontsize="small")
    rate.set_ylabel("deg/s")
    rate.set_xlabel("log time (s)")
    rate.legend(loc="upper right", fontsize="small")
    fig.suptitle("Attitude: estimate and raw sensors")
    fig.savefig(os.path.join(out, "attitude.png"), dpi=100)


def altitude(baro, est, out):
    fig, (alt, climb) = plt.subplots(2, 1, sharex=True, figsize=(10, 6))
    if baro is not None:
        # The baro's altitude is above sea level (ISA); the estimate's above power-up.
        alt.plot(baro["t"], baro["altitude_m"] - baro["altitude_m"][0], ".", ms=2,
                 label="baro (from its first reading)")
    if est is not None:
        alt.plot(est["t"], est["altitude_m"], label="estimate")
        climb.plot(est["t"], est["climb_mps"], label="climb rate, estimate")
    alt.set_ylabel("m")
    alt.legend(loc="upper right", fontsize="small")
    climb.set_ylabel("m/s")
    climb.set_xlabel("log time (s)")
    fig.suptitle("Altitude: estimate and barometer")
    fig.savefig(os.path.join(out, "altitude.png"), dpi=100)


def identification(ident, out):
    fig, (beta, tau) = plt.subplots(2, 1, sharex=True, figsize=(10, 6))
    for i, axis in enumerate(("roll", "pitch", "yaw")):
        beta.plot(ident["t"], np.exp(ident[f"ln_beta[{i}]"]), label=f"β {axis}")
    tau.plot(ident["t"], ident["tau_s"] * 1e3, label="τ")
    beta.set_ylabel("β (rad/s² per unit)")
    beta.set_yscale("log")
    beta.legend(loc="upper right", fontsize="small")
    tau.set_ylabel("τ (ms)")
    tau.set_xlabel("log time (s)")
    last = {k: v[-1] for k, v in ident.items()}
    fig.suptitle("Identified: β = " + ", ".join(f"{np.exp(last[f'ln_beta[{i}]']):.0f}" for i in range(3))
                 + f", τ = {last['tau_s'] * 1e3:.1f} ms")
    fig.savefig(os.path.join(out, "identification.png"), dpi=100)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", help="a TauLink flight log (.ulg)")
    parser.add_argument("--out", required=True, help="folder for the PNGs")
    args = parser.parse_args()
    try:
        log = ULog(args.log)
    except (OSError, ValueError) as e:
        print(f"plot_log: {args.log}: {e}", file=sys.stderr)
        return 1
    os.makedirs(args.out, exist_ok=True)
    imu, est = topic(log, "sensor_imu"), topic(log, "estimate")
    attitude(imu, est, args.out)
    altitude(topic(log, "sensor_baro"), est, args.out)
    ident = topic(log, "identification")
    if ident is not None:
        identification(ident, args.out)
    else:
        print("plot_log: no identification in this log (fly the identification mode)")
    print(f"plot_log: wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
