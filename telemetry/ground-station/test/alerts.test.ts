import { describe, expect, it } from "vitest";
import { Alerts, BATTERY_REPEAT_MS, LINK_LOST_MS, Speaker, armText } from "../src/alerts";
import { apply, initialState } from "../src/model";

const battery = (mv: number) => ({ Battery: { voltage_mv: mv, current_ca: 0, used_mah: 0, remaining_percent: 0 } });
const arm = (armed: boolean, failsafe = false, blockers = 0) => ({ ArmState: { armed, failsafe, arming_blockers: blockers } });

describe("voice alerts", () => {
  it("speaks changes, never the first value", () => {
    const a = new Alerts();
    const s = initialState();
    apply(s, { FlightMode: "Attitude" }, 0);
    apply(s, arm(false), 0);
    expect(a.update(s, 0)).toEqual([]);
    apply(s, { FlightMode: "AltitudeHold" }, 100);
    apply(s, arm(true), 100);
    expect(a.update(s, 100)).toEqual(["Flight mode Altitude hold", "Armed"]);
    expect(a.update(s, 200)).toEqual([]);
    apply(s, arm(true, true), 300);
    expect(a.update(s, 300)).toEqual(["Failsafe"]);
    apply(s, arm(false, false), 400);
    expect(a.update(s, 400)).toEqual(["Disarmed", "Failsafe cleared"]);
  });

  it("telemetry lost after LINK_LOST_MS of silence, regained on the next message", () => {
    const a = new Alerts();
    const s = initialState();
    apply(s, { FlightMode: "RatePid" }, 0);
    expect(a.update(s, 0)).toEqual([]);
    expect(a.update(s, LINK_LOST_MS + 1)).toEqual(["Telemetry lost"]);
    expect(a.update(s, LINK_LOST_MS + 500)).toEqual([]);
    apply(s, { FlightMode: "RatePid" }, 5000);
    expect(a.update(s, 5000)).toEqual(["Telemetry regained"]);
  });

  it("battery levels per cell with hysteresis, repeated at most every BATTERY_REPEAT_MS", () => {
    const a = new Alerts();
    const s = initialState();
    apply(s, battery(16_400), 0);
    expect(a.update(s, 0)).toEqual([]);
    expect(a.cellCount).toBe(4);
    apply(s, battery(13_900), 1);
    expect(a.update(s, 1)).toEqual(["Battery low, 13.9 volts"]);
    apply(s, battery(14_100), 2); // 3.525 V/cell: inside the hysteresis, still low, not repeated
    expect(a.update(s, 2)).toEqual([]);
    expect(a.batteryLevel).toBe("warning");
    apply(s, battery(14_100), 2 + BATTERY_REPEAT_MS);
    expect(a.update(s, 2 + BATTERY_REPEAT_MS)).toEqual(["Battery low, 14.1 volts"]);
    apply(s, battery(13_100), BATTERY_REPEAT_MS + 3);
    expect(a.update(s, BATTERY_REPEAT_MS + 3)).toEqual(["Battery critical, 13.1 volts"]);
    apply(s, battery(14_500), BATTERY_REPEAT_MS + 4);
    expect(a.update(s, BATTERY_REPEAT_MS + 4)).toEqual([]);
    expect(a.batteryLevel).toBe("ok");
  });

  it("arm state text names what blocks arming", () => {
    const s = initialState();
    expect(armText(s)).toBe("—");
    apply(s, arm(false, false, 2 | 8), 0);
    expect(armText(s)).toBe("Disarmed (throttle not low, gains not ready)");
    apply(s, arm(false), 0);
    expect(armText(s)).toBe("Disarmed, ready");
  });

  it("mute silences the speaker", () => {
    const spoken: string[] = [];
    (globalThis as { SpeechSynthesisUtterance?: unknown }).SpeechSynthesisUtterance = class {
      constructor(public text: string) {}
    };
    const synth = { speak: (u: { text: string }) => spoken.push(u.text) } as unknown as SpeechSynthesis;
    const speaker = new Speaker(synth);
    speaker.speak(["Armed"]);
    speaker.muted = true;
    speaker.speak(["Disarmed"]);
    expect(spoken).toEqual(["Armed"]);
  });
});
