// The WebAssembly decoder against the Rust reader: telemetry/wasm/tests/streams.json holds
// streams (in their arrival chunks) and the JSON the Rust reader made of every chunk (kept
// current by `cargo test -p telemetry-wasm`); the wasm build must produce the same text.
import { readFileSync } from "node:fs";
import { fileURLToPath } from "node:url";
import { beforeAll, describe, expect, it } from "vitest";
import { Decoder, Phone, checkSetting, loadWasm, settingChangeFrame, settingValue, settingsTable } from "../src/decoder";
import { fromHex } from "../src/log";

const here = (p: string): string => fileURLToPath(new URL(p, import.meta.url));
interface Stream { name: string; chunks: string[]; decoded: string[] }
const streams = JSON.parse(readFileSync(here("../../wasm/tests/streams.json"), "utf8")) as Stream[];

beforeAll(async () => {
  await loadWasm(readFileSync(here("../src/wasm/telemetry_wasm_bg.wasm")));
});

describe("wasm decoder = Rust reader", () => {
  it("covers the streams", () => expect(streams.length).toBeGreaterThanOrEqual(6));
  for (const s of streams) {
    it(s.name, () => {
      const d = new Decoder();
      const got = s.chunks.map((hex) => d.pushJson(fromHex(hex) ?? new Uint8Array()));
      expect(got).toEqual(s.decoded);
      const drops = s.decoded.join("").split('"Dropped"').length - 1;
      expect(d.dropped).toBe(drops);
    });
  }
});

describe("settings encoders", () => {
  it("round-trips a real setting through its frame", () => {
    const table = settingsTable();
    const kp = table.find((r) => r.name === "pid.roll.kp");
    expect(kp?.kind).toBe("real");
    const frame = settingChangeFrame(kp!.id, 0.004);
    expect(frame?.at(-1)).toBe(0);
    const events = new Decoder().push(frame!);
    expect(events).toHaveLength(1);
    const change = (events[0] as { SettingChange: { id: number; value: number } }).SettingChange;
    expect(change.id).toBe(kp!.id);
    expect(settingValue(kp!.id, change.value)).toBeCloseTo(0.004, 7);
    expect(settingChangeFrame(kp!.id, 5)).toBeUndefined();
  });

  it("gives each number its unit and range, each choice its names", () => {
    const table = settingsTable();
    const rate = table.find((r) => r.name === "rate.max_dps")!;
    expect([rate.kind, rate.unit, rate.min, rate.max]).toEqual(["real", "°/s", 30, 2000]);
    expect(rate.doc).toBe("Rate modes: the rate full stick commands.");
    const frame = table.find((r) => r.name === "mixer.frame")!;
    expect([frame.kind, frame.choices]).toEqual(["choice", ["quad-x", "quad-plus", "hex-x"]]);
  });

  it("says why the flight side would refuse a value", () => {
    const table = settingsTable();
    const id = (name: string): number => table.find((r) => r.name === name)!.id;
    expect(checkSetting(id("pid.roll.kp"), 0.004)).toEqual({ wire: new Int32Array(new Float32Array([0.004]).buffer)[0] });
    expect(checkSetting(id("pid.roll.kp"), 5)).toEqual({ refused: "5 is above the largest value, 1" });
    expect(checkSetting(id("rate.max_dps"), 10)).toEqual({ refused: "10 is below the smallest value, 30 °/s" });
    expect(checkSetting(id("battery.cells"), 2.5)).toEqual({ refused: "2.5 is not a whole number" });
    expect(checkSetting(id("battery.cells"), NaN)).toEqual({ refused: "not a number" });
  });
});

describe("the phone's half", () => {
  it("asks the module, signs nothing before its grant, and holds the phrase rule", () => {
    const kp = settingsTable().find((r) => r.name === "pid.roll.kp")!;
    const phone = new Phone("amber kettle under the oak");
    expect(phone.standing).toBe("unknown");
    // The Hello is a module record: the page's own decoder reads it back as one.
    expect(new Decoder().push(phone.hello())).toEqual(["Hello"]);
    const check = checkSetting(kp.id, 0.004);
    if (!("wire" in check)) throw new Error(check.refused);
    expect(phone.signChange(kp.id, check.wire)).toBeUndefined();
    expect(phone.onRefused({ id: kp.id, reason: "NotAuthenticated", session: 42, counter: 0 })).toBeUndefined();
    // A module's refusal is the phone's standing.
    expect(phone.onModuleRecord({ Answer: { outcome: { Refused: "NoPhrase" }, counter: 0 } })).toBeUndefined();
    expect(phone.standing).toBe("refused:NoPhrase");
    expect(() => new Phone("  ")).toThrow();
    expect(() => new Phone("short")).toThrow(/12/);
    expect(() => new Phone("correct horse battery staple")).toThrow(/famous/);
  });
});
