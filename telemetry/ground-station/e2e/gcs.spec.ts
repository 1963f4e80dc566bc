// The ground station in Chromium against `taulink-sim --serve`: each page gets a fresh
// firmware-in-the-loop world (flight-sitl: the flight firmware's FlightApp and the module's
// App on virtual radios, the quad flown by a scripted pilot — on the ground until 8.5 s after
// power-up, armed from ≈ 10 s, rate mode from 20 s to 28 s, landed and disarmed by ≈ 60 s);
// the page is the phone on the module's HM-10. `/api/sent` tells what the server sent the
// page (decoded) and which setting changes the FlightApp took.
import { spawn } from "node:child_process";
import { readFileSync } from "node:fs";
import { fileURLToPath } from "node:url";
import { expect, test, type Page } from "@playwright/test";
import { Decoder, loadWasm } from "../src/decoder";
import * as fmt from "../src/format";
import { parseLog } from "../src/log";
import { MODE_NAMES, type Event, type FlightMode } from "../src/messages";

interface Sent {
  last: Record<string, Record<string, number> | string>;
  applied: { id: number; value: number }[];
  refused: { id: number; reason: string }[];
}

const sent = async (page: Page): Promise<Sent> => (await page.request.get("/api/sent")).json() as Promise<Sent>;
const text = async (page: Page, label: string): Promise<string> =>
  (await page.getByLabel(label, { exact: true }).textContent()) ?? "";

/** The page's values next to what the flight side last sent, formatted the page's way. */
async function compare(page: Page): Promise<[string[], string[]]> {
  const s = (await sent(page)).last as Record<string, Record<string, number>>;
  const shown = await Promise.all(
    ["Battery voltage", "Uplink LQ", "Downlink LQ", "Flight mode", "Roll", "Pitch", "Heading", "Armed"].map((l) => text(page, l)),
  );
  const { Battery: b, LinkStats: l, Attitude: a } = s;
  const mode = (s as unknown as Record<string, FlightMode | undefined>).FlightMode;
  const arm = s.ArmState as unknown as { armed: boolean } | undefined;
  const want = [
    b ? fmt.volts(b.voltage_mv!) : "?",
    l ? fmt.percent(l.uplink_lq!) : "?",
    l ? fmt.percent(l.downlink_lq!) : "?",
    mode ? MODE_NAMES[mode] : "?",
    a ? fmt.degrees(a.roll_cdeg!) : "?",
    a ? fmt.degrees(a.pitch_cdeg!) : "?",
    a ? fmt.heading(a.yaw_cdeg!) : "?",
    arm ? fmt.yesNo(arm.armed) : "?",
  ];
  return [shown, want];
}

test.beforeEach(async ({ page }) => {
  await page.addInitScript(() => {
    const spoken: string[] = [];
    (window as unknown as { spoken: string[] }).spoken = spoken;
    window.speechSynthesis.speak = (u: SpeechSynthesisUtterance) => void spoken.push(u.text);
  });
});

test("connects and shows what the simulator sent", async ({ page }) => {
  await page.goto("/?sim");
  await expect(page.getByRole("status", { name: "Connection status" })).toHaveText("connected: simulator");
  await expect
    .poll(async () => {
      const [shown, want] = await compare(page);
      return shown.join(" | ") === want.join(" | ") && !want.includes("?") ? "equal" : `${shown} vs ${want}`;
    }, { timeout: 20_000 })
    .toBe("equal");
  // The BrushedSparky world's 1S pack.
  await expect(page.getByLabel("Battery voltage", { exact: true })).toHaveText(/^4\.\d\d V$/);
  await expect(page.getByLabel("Uplink LQ", { exact: true })).toHaveText(/^\d+ %$/);
});

test("arming and a flight-mode change are spoken; mute silences the next change", async ({ page }) => {
  await page.goto("/?sim");
  await expect(page.getByLabel("Flight mode", { exact: true })).toHaveText("Attitude");
  // The pilot arms ≈ 10 s after power-up and flips the mode switch to rate (factory: rate
  // PID) at 20 s.
  await expect
    .poll(async () => page.evaluate(() => (window as unknown as { spoken: string[] }).spoken.join(";")), { timeout: 30_000 })
    .toContain("Flight mode Rate PID");
  expect(await page.evaluate(() => (window as unknown as { spoken: string[] }).spoken.join(";"))).toContain("Armed");
  await expect(page.getByLabel("Flight mode", { exact: true })).toHaveText("Rate PID");
  // Armed and flying: settings are no longer offered.
  await expect(page.getByLabel("Armed", { exact: true })).toHaveText("Yes");
  await expect(page.getByRole("button", { name: "Set" }).first()).toBeDisabled();
  // Mute: the switch back to attitude at 28 s is shown, not spoken.
  await page.getByRole("button", { name: "Mute" }).click();
  const before = await page.evaluate(() => (window as unknown as { spoken: string[] }).spoken.length);
  await expect(page.getByLabel("Flight mode", { exact: true })).toHaveText("Attitude", { timeout: 15_000 });
  await page.waitForTimeout(1_000);
  expect(await page.evaluate(() => (window as unknown as { spoken: string[] }).spoken.length)).toBe(before);
});

/** The binding phrase the simulated module holds (`taulink-sim --serve` prints it). */
const SERVE_PHRASE = "taulink served demo";

test("opened from the URL taulink-sim --serve prints, the page connects by itself", async ({ page }) => {
  // A server of its own on a free port, started as a user starts it; its first line is the URL.
  const server = spawn(fileURLToPath(new URL("../../../target/release/taulink-sim", import.meta.url)), ["--serve", "127.0.0.1:0", "--dist", "dist"], {
    cwd: fileURLToPath(new URL("..", import.meta.url)),
    stdio: ["ignore", "pipe", "inherit"],
  });
  try {
    const url = await new Promise<string>((resolve, reject) => {
      let out = "";
      server.stdout.on("data", (d: Buffer) => {
        out += d.toString();
        const m = /open (http:\/\/\S+)/.exec(out);
        if (m) resolve(m[1]!);
      });
      server.on("exit", (code) => reject(new Error(`taulink-sim exited (${code}): ${out}`)));
    });
    await page.goto(url);
    // No click: the status and the values arrive by themselves.
    await expect(page.getByRole("status", { name: "Connection status" })).toHaveText("connected: simulator");
    await expect(page.getByLabel("Battery voltage", { exact: true })).toHaveText(/^\d\.\d\d V$/, { timeout: 10_000 });
  } finally {
    server.kill();
  }
});

test("one element per accessible name", async ({ page }) => {
  await page.goto("/");
  await expect(page.getByLabel("Setting pid.roll.kp")).toBeVisible();
  // Every name given on the page (aria-label, and a button's text where it has none).
  const names = await page.evaluate(() =>
    [...document.querySelectorAll("[aria-label], button")].map((e) => e.getAttribute("aria-label") ?? e.textContent?.trim() ?? ""),
  );
  expect(names.length).toBeGreaterThan(100);
  const seen = new Set<string>();
  const twice = names.filter((n) => seen.size === seen.add(n.toLowerCase()).size);
  expect(twice).toEqual([]);
  // Outside the per-setting rows, no name is part of another, so a name asked for as
  // Playwright or a screen reader's search does (case-insensitive, in part) finds one element:
  // the heading value is "Heading", the compass strip "Compass strip".
  const fixed = names.filter((n) => !/^(Setting|New value for|Set) [a-z]/.test(n));
  for (const name of fixed) {
    const within = fixed.filter((other) => other !== name && other.toLowerCase().includes(name.toLowerCase()));
    expect(within, `"${name}" is part of`).toEqual([]);
  }
  await expect(page.getByLabel("Heading")).toHaveCount(1);
  await expect(page.getByRole("img", { name: "Compass strip" })).toHaveCount(1);
});

test("an enum setting is chosen by its name, numbers show their unit and range, refusals say why", async ({ page }) => {
  await page.goto("/?sim");
  await expect(page.getByRole("status", { name: "Connection status" })).toHaveText("connected: simulator");
  await page.getByLabel("Binding phrase").fill(SERVE_PHRASE);
  await page.getByRole("button", { name: "Use phrase" }).click();
  await expect(page.getByLabel("Phrase status")).toHaveText("phrase confirmed", { timeout: 10_000 });
  // A number: its range and unit beside its name; a value outside it is not sent, and why.
  await page.getByLabel("Filter settings").fill("rate.max_dps");
  await expect(page.getByRole("row", { name: /rate\.max_dps/ })).toContainText("30 … 2000 °/s");
  await page.getByLabel("New value for rate.max_dps").fill("5000");
  await page.getByRole("button", { name: "Set rate.max_dps" }).click();
  await expect(page.getByRole("status", { name: "Settings status" })).toHaveText(
    "rate.max_dps: 5000 is above the largest value, 2000 °/s",
  );
  // A choice: picked from its names, echoed by name once the flight side holds it.
  await page.getByLabel("Filter settings").fill("mode.switch_high");
  await page.getByLabel("New value for mode.switch_high").selectOption({ label: "horizon" });
  await page.getByRole("button", { name: "Set mode.switch_high" }).click();
  await expect(page.getByLabel("Setting mode.switch_high")).toHaveText("horizon", { timeout: 10_000 });
  const applied = (await sent(page)).applied;
  expect(applied).toHaveLength(1);
  // The wire carries the choice's index: horizon is the fourth of the modes.
  expect(applied[0]!.value).toBe(3);
});

test("a setting change round-trips to the flight side", async ({ page }) => {
  await page.goto("/?sim");
  await expect(page.getByRole("status", { name: "Connection status" })).toHaveText("connected: simulator");
  await page.getByLabel("Binding phrase").fill(SERVE_PHRASE);
  await page.getByRole("button", { name: "Use phrase" }).click();
  // The simulated module's App ran CPace with the page and granted the change key.
  await expect(page.getByLabel("Phrase status")).toHaveText("phrase confirmed", { timeout: 10_000 });
  await page.getByLabel("Filter settings").fill("pid.roll.kp");
  await page.getByLabel("New value for pid.roll.kp").fill("0.004");
  await page.getByRole("row", { name: /pid\.roll\.kp/ }).getByRole("button", { name: "Set" }).click();
  // The flight side's echo, shown as the value it holds.
  await expect(page.getByLabel("Setting pid.roll.kp")).toHaveText("0.004", { timeout: 10_000 });
  const bits = new Int32Array(new Float32Array([0.004]).buffer)[0];
  const applied = (await sent(page)).applied;
  expect(applied).toHaveLength(1);
  expect(applied[0]!.value).toBe(bits);
});

test("a wrong phrase is refused by the module and nothing can be signed", async ({ page }) => {
  await page.goto("/?sim");
  await expect(page.getByRole("status", { name: "Connection status" })).toHaveText("connected: simulator");
  await page.getByLabel("Binding phrase").fill("amber kettle not the demo");
  await page.getByRole("button", { name: "Use phrase" }).click();
  await expect(page.getByLabel("Phrase status")).toHaveText("refused: the phrase above is not the module's", {
    timeout: 10_000,
  });
  await page.getByLabel("Filter settings").fill("pid.roll.kp");
  await page.getByLabel("New value for pid.roll.kp").fill("0.004");
  await page.getByRole("row", { name: /pid\.roll\.kp/ }).getByRole("button", { name: "Set" }).click();
  await expect(page.getByRole("status", { name: "Connection status" })).toHaveText(
    "enter the binding phrase first: the module must confirm it before changes can be signed",
  );
  await expect(page.getByLabel("Setting pid.roll.kp")).toHaveText("—");
  const log = await sent(page);
  expect(log.applied).toHaveLength(0);
});

test("a phrase under the rule is refused in the page", async ({ page }) => {
  await page.goto("/?sim");
  await page.getByLabel("Binding phrase").fill("short");
  await page.getByRole("button", { name: "Use phrase" }).click();
  await expect(page.getByRole("status", { name: "Connection status" })).toHaveText(/shorter than 12 characters/);
  await expect(page.getByLabel("Phrase status")).toHaveText("not asked");
});

test("the module's phrase set from the page after proving its phrase", async ({ page }) => {
  await page.goto("/?sim");
  await expect(page.getByRole("status", { name: "Connection status" })).toHaveText("connected: simulator");
  await page.getByLabel("Binding phrase").fill(SERVE_PHRASE);
  await page.getByRole("button", { name: "Use phrase" }).click();
  await expect(page.getByLabel("Phrase status")).toHaveText("phrase confirmed", { timeout: 10_000 });
  await page.getByLabel("New module phrase").fill("brass lantern by the weir");
  await page.getByRole("button", { name: "Set module phrase" }).click();
  // The simulated module's App took the sealed derivation.
  await expect(page.getByLabel("Module phrase status")).toHaveText("module phrase set: bind again with it", {
    timeout: 10_000,
  });
});

test("the module's phrase needs its current phrase first", async ({ page }) => {
  await page.goto("/?sim");
  await expect(page.getByRole("status", { name: "Connection status" })).toHaveText("connected: simulator");
  await page.getByLabel("New module phrase").fill("brass lantern by the weir");
  await page.getByRole("button", { name: "Set module phrase" }).click();
  await expect(page.getByLabel("Module phrase status")).toHaveText("enter the module's current phrase above first");
});

test("a recorded log replays", async ({ page, context }) => {
  await page.goto("/?sim");
  await expect(page.getByLabel("Battery voltage", { exact: true })).toHaveText(/V$/);
  await page.getByRole("button", { name: "Record" }).click();
  await page.waitForTimeout(3_000);
  await page.getByRole("button", { name: "Record" }).click();
  const downloading = page.waitForEvent("download");
  await page.getByRole("button", { name: "Save log" }).click();
  const path = await (await downloading).path();
  const log = readFileSync(path, "utf8");
  // What the log holds, decoded in Node by the same WebAssembly build.
  await loadWasm(readFileSync(fileURLToPath(new URL("../src/wasm/telemetry_wasm_bg.wasm", import.meta.url))));
  const decoder = new Decoder();
  const last: Record<string, unknown> = {};
  for (const c of parseLog(log)) {
    for (const e of decoder.push(c.bytes) as Event[]) if (e !== "Dropped") Object.assign(last, e);
  }
  const battery = last.Battery as { voltage_mv: number };
  const attitude = last.Attitude as { roll_cdeg: number };
  expect(battery && attitude).toBeTruthy();

  const replay = await context.newPage();
  await replay.goto("/");
  await replay.getByLabel("Open log").setInputFiles({ name: "flight.tlog", mimeType: "text/plain", buffer: Buffer.from(log) });
  await expect(replay.getByRole("status", { name: "Connection status" })).toHaveText("replayed flight.tlog", { timeout: 10_000 });
  await expect(replay.getByLabel("Battery voltage", { exact: true })).toHaveText(fmt.volts(battery.voltage_mv));
  await expect(replay.getByLabel("Roll", { exact: true })).toHaveText(fmt.degrees(attitude.roll_cdeg));
  await expect(replay.getByLabel("Flight mode", { exact: true })).toHaveText(MODE_NAMES[last.FlightMode as FlightMode]);
});

test("works offline after the first load", async ({ page, context }) => {
  await page.goto("/");
  await page.evaluate(async () => {
    await navigator.serviceWorker.ready;
  });
  await page.reload();
  await context.setOffline(true);
  await page.reload();
  await expect(page.getByRole("heading", { name: "TauLink" })).toBeVisible();
  await expect(page.getByLabel("Setting pid.roll.kp")).toHaveText("—");
  await context.setOffline(false);
});
