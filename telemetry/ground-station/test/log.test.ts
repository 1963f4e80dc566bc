import { describe, expect, it } from "vitest";
import { LOG_HEADER, Recorder, csvByType, fromHex, parseLog, toHex } from "../src/log";
import type { Event } from "../src/messages";

describe("logs", () => {
  it("records and parses back chunk for chunk", () => {
    const r = new Recorder(1000);
    r.add(1000, new Uint8Array([1, 2, 0]));
    r.add(1250.4, new Uint8Array([0xff]));
    const text = r.text();
    expect(text).toBe(`${LOG_HEADER}\n0 010200\n250 ff\n`);
    expect(parseLog(text)).toEqual([
      { t: 0, bytes: new Uint8Array([1, 2, 0]) },
      { t: 250, bytes: new Uint8Array([0xff]) },
    ]);
  });

  it("refuses files that are not logs", () => {
    expect(() => parseLog("hello")).toThrow(/not a TauLink/);
    expect(() => parseLog(`${LOG_HEADER}\n0 0g\n`)).toThrow(/line 2/);
    expect(fromHex("abc")).toBeUndefined();
    expect(toHex(new Uint8Array([0, 15, 255]))).toBe("000fff");
  });

  it("exports one CSV per message type", () => {
    const events: Record<string, Event[]> = {
      a: [{ Battery: { voltage_mv: 16000, current_ca: 5, used_mah: 1, remaining_percent: 0 } }, "Dropped"],
      b: [{ FlightMode: "RatePid" }, { Battery: { voltage_mv: 15990, current_ca: 6, used_mah: 2, remaining_percent: 0 } }],
    };
    const csv = csvByType(
      [{ t: 0, bytes: new Uint8Array([0xa]) }, { t: 20, bytes: new Uint8Array([0xb]) }],
      (b) => events[b[0] === 0xa ? "a" : "b"] ?? [],
    );
    expect([...csv.keys()]).toEqual(["Battery", "FlightMode"]);
    expect(csv.get("Battery")).toBe("t_ms,voltage_mv,current_ca,used_mah,remaining_percent\n0,16000,5,1,0\n20,15990,6,2,0\n");
    expect(csv.get("FlightMode")).toBe("t_ms,value\n20,RatePid\n");
  });
});
