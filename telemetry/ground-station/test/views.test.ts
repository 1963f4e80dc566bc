import { describe, expect, it } from "vitest";
import { heading, real, volts } from "../src/format";
import { HISTORY_MS } from "../src/model";
import { pieces, parseSettingLine } from "../src/transports";
import { chartX, fitTrack, headingDeg, horizonTransform, localM } from "../src/views";

describe("views and formats", () => {
  it("horizon and heading", () => {
    expect(horizonTransform(10, 5)).toBe("rotate(-10.0 100 100) translate(0 10.0)");
    expect(headingDeg(-9000)).toBe(270);
    expect(heading(-9000)).toBe("270°");
    expect(heading(500)).toBe("005°");
    expect(volts(16_420)).toBe("16.42 V");
    expect(real(Math.fround(0.3))).toBe("0.3");
    expect(real(Math.fround(0.00004))).toBe("0.00004");
  });

  it("strip chart time axis", () => {
    expect(chartX(1000, 1000, 300)).toBe(300);
    expect(chartX(1000 - HISTORY_MS, 1000, 300)).toBe(0);
  });

  it("track fits the canvas", () => {
    const o = { lat: 47, lon: 8 };
    const p = { lat: 47.001, lon: 8 };
    expect(localM(o, p)[1]).toBeCloseTo(111.2, 0);
    const { scale } = fitTrack([o, p], 220, 220);
    expect(scale * 111.19).toBeCloseTo(200, 0);
  });

  it("BLE writes of 20 bytes; console lines", () => {
    expect(pieces(new Uint8Array(45), 20).map((p) => p.length)).toEqual([20, 20, 5]);
    expect(parseSettingLine("pid.roll.kp = 0.003\r")).toEqual(["pid.roll.kp", "0.003"]);
    expect(parseSettingLine("ok")).toBeUndefined();
  });
});
