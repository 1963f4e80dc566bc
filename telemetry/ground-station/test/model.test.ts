import { describe, expect, it } from "vitest";
import { HISTORY_MS, TRACK_STEP_M, apply, distanceM, initialState } from "../src/model";

const link = (lq: number) => ({
  LinkStats: { uplink_rssi_dbm: -80, uplink_lq: lq, downlink_rssi_dbm: -90, downlink_lq: lq - 1, rate_mode: 2, received: 1, missed: 0, failsafes: 0 },
});
const gps = (lat: number, lon: number, fix: "None" | "Fix3d" = "Fix3d") => ({
  Gps: { latitude_e7: lat * 1e7, longitude_e7: lon * 1e7, altitude_cm: 0, ground_speed_cm_s: 0, course_cdeg: 0, satellites: 9, fix },
});

describe("model", () => {
  it("keeps the latest of each message and counts drops", () => {
    const s = initialState();
    apply(s, { FlightMode: "Attitude" }, 1);
    apply(s, "Dropped", 2);
    apply(s, { FlightMode: "RatePid" }, 3);
    apply(s, { SettingChange: { id: 4, value: 9 } }, 4);
    expect(s.mode).toBe("RatePid");
    expect(s.settings.get(4)).toBe(9);
    expect([s.messages, s.dropped, s.lastMessageMs]).toEqual([3, 1, 4]);
  });

  it("keeps the home the flight side reports set", () => {
    const s = initialState();
    const home = { latitude_e7: 470_654_321, longitude_e7: 80_123_456, altitude_cm: 50_000, set: true };
    apply(s, { Home: home }, 1);
    expect(s.home).toEqual(home);
    apply(s, { Home: { ...home, set: false } }, 2);
    expect(s.home).toBeUndefined();
  });

  it("keeps the flight side's last refusal until that setting is applied", () => {
    const s = initialState();
    const refused = { id: 4, reason: "NotAuthenticated" as const, session: 7, counter: 0 };
    apply(s, { ChangeRefused: refused }, 1);
    expect(s.refused).toEqual(refused);
    apply(s, { SettingChange: { id: 5, value: 1 } }, 2);
    expect(s.refused).toEqual(refused);
    apply(s, { SettingChange: { id: 4, value: 9 } }, 3);
    expect(s.refused).toBeUndefined();
  });

  it("keeps only the last HISTORY_MS of link samples", () => {
    const s = initialState();
    for (let t = 0; t <= 2 * HISTORY_MS; t += 1000) apply(s, link(90), t);
    expect(s.linkHistory[0]?.t).toBe(HISTORY_MS);
    expect(s.linkHistory.at(-1)).toEqual({ t: 2 * HISTORY_MS, upLq: 90, dnLq: 89, upRssi: -80, dnRssi: -90 });
  });

  it("adds track points only with a fix and after TRACK_STEP_M", () => {
    const s = initialState();
    apply(s, gps(47, 8, "None"), 0);
    apply(s, gps(47, 8), 1);
    apply(s, gps(47 + 1e-7, 8), 2); // 1 cm: same point
    apply(s, gps(47 + 1e-4, 8), 3); // 11 m
    expect(s.track).toHaveLength(2);
    expect(distanceM(s.track[0]!, s.track[1]!)).toBeGreaterThan(TRACK_STEP_M);
    expect(distanceM({ lat: 0, lon: 0 }, { lat: 0, lon: 1 })).toBeCloseTo(111_195, -1);
  });
});
