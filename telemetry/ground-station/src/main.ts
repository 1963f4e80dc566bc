/**
 * The app: connects a transport, runs every received chunk through the Rust decoder, folds
 * the events into the model, renders it, speaks alerts, records and replays logs, and sends
 * setting changes. No decoding or protocol logic here beyond calling the WebAssembly side.
 */
import "./style.css";
import { Alerts, Speaker, armText } from "./alerts";
import {
  Decoder,
  Phone,
  checkSetting,
  loadWasm,
  settingValue,
  settingsTable,
  type SettingRow,
} from "./decoder";
import type { ModuleAnswer, ModuleEvent, ModuleRefusal } from "./messages";
import * as fmt from "./format";
import { type Chunk, Recorder, csvByType, parseLog } from "./log";
import { MODE_NAMES, RATE_MODES, type Event, type RefuseReason } from "./messages";
import { type State, apply, initialState } from "./model";
import { type Console, type Transport, connectBluetooth, connectSerial, connectWebSocket, parseSettingLine } from "./transports";
import { Horizon, drawStrip, drawTrack, headingDeg } from "./views";

const $ = <T extends HTMLElement = HTMLElement>(id: string): T => {
  const el = document.getElementById(id);
  if (!el) throw new Error(`#${id} missing`);
  return el as T;
};

let state: State = initialState();
let decoder: Decoder;
let transport: Transport | undefined;
let usb: Console | undefined;
let recorder: Recorder | undefined;
let lastLog: string | undefined;
let replayTimer: ReturnType<typeof setTimeout> | undefined;
let alerts = new Alerts();
const speaker = new Speaker();
let horizon: Horizon;
let settings: SettingRow[] = [];
/** The phone's half with the binding phrase (in memory only: gone with the page). */
let phone: Phone | undefined;
/** Why the page itself did not send the last value typed (shown before the flight side's refusals). */
let pageRefusal: string | undefined;
/** Console values by setting name (USB), shown when no link echo is there. */
const consoleValues = new Map<string, string>();

function status(text: string): void {
  $("status").textContent = text;
}

function set(id: string, text: string, cls = ""): void {
  const el = $(id);
  if (el.textContent !== text) el.textContent = text;
  el.className = `${el.classList.contains("big") ? "big " : ""}${cls}`;
}

function onBytes(bytes: Uint8Array): void {
  recorder?.add(performance.now(), bytes);
  const now = performance.now();
  for (const e of decoder.push(bytes)) {
    // The module's exchange with the phone: its phone half reads them.
    if (typeof e === "object" && ("Challenge" in e || "Granted" in e || "Answer" in e)) {
      void onModuleRecord(e);
      continue;
    }
    // A refusal that only taught the phone the flight side's session: signed again, once.
    if (typeof e === "object" && "ChangeRefused" in e) {
      const again = phone?.onRefused(e.ChangeRefused);
      if (again && transport) {
        void transport.send(again);
        continue;
      }
    }
    apply(state, e, now);
  }
  $("record").title = recorder ? `${recorder.chunks} chunks` : "";
}

function render(): void {
  const now = performance.now();
  speaker.speak(alerts.update(state, now));
  const s = state;
  if (s.attitude) {
    const a = s.attitude;
    horizon.update(a.roll_cdeg / 100, a.pitch_cdeg / 100, headingDeg(a.yaw_cdeg));
    set("roll", fmt.degrees(a.roll_cdeg));
    set("pitch", fmt.degrees(a.pitch_cdeg));
    set("heading", fmt.heading(a.yaw_cdeg));
  }
  if (s.mode) set("mode", MODE_NAMES[s.mode]);
  if (s.arm) {
    set("armed", fmt.yesNo(s.arm.armed), s.arm.armed ? "warn" : "");
    set("arm-state", armText(s));
    set("failsafe", fmt.yesNo(s.arm.failsafe), s.arm.failsafe ? "bad" : "");
  }
  if (s.battery) {
    const b = s.battery;
    const level = alerts.batteryLevel;
    const cls = level === "critical" ? "crit" : level === "warning" ? "warn" : "";
    set("voltage", fmt.volts(b.voltage_mv), cls);
    const cells = alerts.cellCount;
    set("cell", cells ? `${fmt.volts(b.voltage_mv / cells)} (${cells}S)` : "—", cls);
    set("current", fmt.amps(b.current_ca));
    set("used", `${b.used_mah} mAh`);
  }
  if (s.link) {
    const l = s.link;
    set("up-lq", fmt.percent(l.uplink_lq), l.uplink_lq < 50 ? "bad" : "");
    set("dn-lq", fmt.percent(l.downlink_lq), l.downlink_lq < 50 ? "bad" : "");
    set("up-rssi", fmt.dbm(l.uplink_rssi_dbm));
    set("dn-rssi", fmt.dbm(l.downlink_rssi_dbm));
    set("rate", RATE_MODES[l.rate_mode] ?? `code ${l.rate_mode}`);
    set("failsafes", String(l.failsafes));
  }
  if (s.tags) {
    const t = s.tags;
    const counts = t.down === undefined ? `${t.up} at the quad` : `${t.down} here / ${t.up} at the quad`;
    set("tag-failures", t.alert ? `${counts} — ALERT: forged or replayed frames` : counts, t.alert ? "bad" : "");
  }
  const tEnd = s.lastMessageMs ?? now;
  drawStrip($<HTMLCanvasElement>("chart-lq"), s.linkHistory, tEnd, [[(x) => x.upLq, "#66bb6a"], [(x) => x.dnLq, "#4fc3f7"]], [0, 100], "LQ %");
  drawStrip($<HTMLCanvasElement>("chart-rssi"), s.linkHistory, tEnd, [[(x) => x.upRssi, "#66bb6a"], [(x) => x.dnRssi, "#4fc3f7"]], [-120, -20], "RSSI dBm");
  if (s.gps) {
    const g = s.gps;
    set("position", fmt.latLon(g.latitude_e7, g.longitude_e7));
    set("altitude", `${(g.altitude_cm / 100).toFixed(1)} m`);
    set("speed", `${(g.ground_speed_cm_s / 100).toFixed(1)} m/s`);
    set("fix", `${g.fix === "Fix3d" ? "3D" : g.fix === "Fix2d" ? "2D" : "none"}, ${g.satellites} sats`);
    drawTrack($<HTMLCanvasElement>("track"), s.track);
  }
  if (s.home) {
    set("home", `${fmt.latLon(s.home.latitude_e7, s.home.longitude_e7)}, ${(s.home.altitude_cm / 100).toFixed(1)} m`);
  }
  renderSysid();
  renderSettingValues();
}

function renderSysid(): void {
  const rows = (["Roll", "Pitch", "Yaw"] as const).flatMap((axis) => {
    const r = state.sysid[axis];
    return r ? [`<tr><td>${axis}</td><td>${r.beta1.toFixed(0)}</td><td>${r.beta2.toFixed(0)}</td><td>${(r.tau_s * 1000).toFixed(1)}</td><td>${r.noise.toPrecision(3)}</td></tr>`] : [];
  });
  const html = rows.length ? rows.join("") : `<tr><td colspan="5">none yet</td></tr>`;
  const body = $("sysid-rows");
  if (body.innerHTML !== html) body.innerHTML = html;
}

/** A setting's value as shown: a choice by its name, a number with its unit. */
function valueText(row: SettingRow, v: number): string {
  if (row.kind === "choice") return row.choices?.[v] ?? String(v);
  const n = row.kind === "real" ? fmt.real(v) : String(v);
  return row.unit ? `${n} ${row.unit}` : n;
}

function shownValue(row: SettingRow): string {
  const wire = state.settings.get(row.id);
  if (wire !== undefined) {
    const v = settingValue(row.id, wire);
    return v === undefined ? "?" : valueText(row, v);
  }
  return consoleValues.get(row.name) ?? "—";
}

const REFUSALS: Record<RefuseReason, string> = {
  Armed: "refused: armed",
  NotAuthenticated: "refused: not signed with the link's change key",
  Replayed: "refused: replayed",
  NoPhrase: "refused: the flight side has no keyed link",
  Invalid: "refused: out of range, or the other settings would not run with it",
};

function renderSettingValues(): void {
  const r = state.refused;
  const name = r ? (settings.find((row) => row.id === r.id)?.name ?? `#${r.id}`) : "";
  const refusal = pageRefusal ?? (r ? `${name} ${REFUSALS[r.reason]}` : undefined);
  set("settings-status", refusal ?? "", refusal ? "bad" : "");
  // The flight side refuses changes while armed; the page does not offer them then.
  const armed = state.arm?.armed === true;
  for (const b of document.querySelectorAll<HTMLButtonElement>("button[data-set], #module-phrase-send")) {
    if (b.disabled !== armed) {
      b.disabled = armed;
      b.title = armed ? "refused while armed" : "";
    }
  }
  for (const row of settings) {
    const el = document.getElementById(`set-${row.id}`);
    if (el) {
      const v = shownValue(row);
      if (el.textContent !== v) el.textContent = v;
    }
  }
}

/** Where a number may go, with its unit ("30 … 2000 °/s"); a choice's names. */
function rangeText(row: SettingRow): string {
  if (row.kind === "choice") return (row.choices ?? []).join(" · ");
  const [lo, hi] = [row.min ?? 0, row.max ?? 0].map((v) => (row.kind === "real" ? fmt.real(v) : String(v)));
  return `${lo} … ${hi}${row.unit ? ` ${row.unit}` : ""}`;
}

/** A choice is picked by name from its list; a number is typed, with its range shown. */
function newValueControl(row: SettingRow): string {
  const label = `aria-label="New value for ${row.name}" data-id="${row.id}"`;
  if (row.kind === "choice") {
    const options = (row.choices ?? []).map((c, i) => `<option value="${i}">${c}</option>`).join("");
    return `<select ${label}><option value="" selected>choose…</option>${options}</select>`;
  }
  const step = row.kind === "whole" ? "1" : "any";
  return `<input ${label} type="number" inputmode="decimal" min="${row.min}" max="${row.max}" step="${step}" placeholder="${rangeText(row)}" />`;
}

function buildSettings(): void {
  settings = settingsTable();
  const filter = ($<HTMLInputElement>("settings-filter").value || "").trim();
  $("settings-rows").innerHTML = settings
    .filter((r) => r.name.includes(filter))
    .map((r) =>
      `<tr><td title="${r.doc}">${r.name}<br /><small class="range">${rangeText(r)}</small></td>` +
      `<td id="set-${r.id}" aria-label="Setting ${r.name}">—</td>` +
      `<td>${newValueControl(r)}</td>` +
      `<td><button type="button" data-set="${r.id}" aria-label="Set ${r.name}">Set</button></td></tr>`)
    .join("");
  renderSettingValues();
}

/** Sends `value` (a number, or a choice's index) for `row`; a refused value is explained. */
async function sendSetting(row: SettingRow, value: number): Promise<void> {
  const check = checkSetting(row.id, value);
  pageRefusal = "refused" in check ? `${row.name}: ${check.refused}` : undefined;
  renderSettingValues();
  if ("refused" in check) return;
  const shown = valueText(row, value);
  if (usb) {
    // The console reads a choice by its name and a number without its unit.
    await usb.command(`set ${row.name} ${row.kind === "choice" ? shown : String(value)}`);
    await usb.command(`get ${row.name}`);
    return;
  }
  if (!phone || !phone.standing.startsWith("granted")) {
    status("enter the binding phrase first: the module must confirm it before changes can be signed");
    return;
  }
  const frame = phone.signChange(row.id, check.wire);
  if (!frame) {
    status("the module has no keyed flight link yet: bind first");
    return;
  }
  if (!transport) {
    status("connect first to change settings");
    return;
  }
  await transport.send(frame);
  status(`${row.name} → ${shown} sent; waiting for the flight side's report`);
}

/** A new module phrase is on its way (until the module answers). */
let modulePhraseSent = false;

const MODULE_REFUSALS: Record<ModuleRefusal, string> = {
  Armed: "refused: armed",
  NotAuthenticated: "refused: the phrase above is not the module's",
  Replayed: "refused: replayed",
  NoPhrase: "the module has no phrase: set it on the radio first",
  NoSession: "no session with the module: enter the phrase again",
  Locked: "refused: too many wrong phrases, restart the module",
  Invalid: "refused: not a valid phrase",
};

const STANDING: Record<string, string> = {
  unknown: "not confirmed yet",
  granted: "phrase confirmed",
  "granted-no-link": "phrase confirmed (no keyed flight link yet)",
};

function showStanding(): void {
  const st = phone?.standing ?? "unknown";
  const refused = st.startsWith("refused:") ? (st.slice(8) as ModuleRefusal) : undefined;
  const text = refused ? MODULE_REFUSALS[refused] : (STANDING[st] ?? st);
  set("phrase-standing", phone ? text : "not asked", refused ? "bad" : st.startsWith("granted") ? "good" : "");
}

async function onModuleRecord(record: ModuleEvent): Promise<void> {
  const next = phone?.onModuleRecord(record);
  showStanding();
  if (next && transport) await transport.send(next);
  if ("Answer" in record && modulePhraseSent) onModuleAnswer(record.Answer);
}

function onModuleAnswer(answer: ModuleAnswer): void {
  const o = answer.outcome;
  if (o === "Applied") {
    modulePhraseSent = false;
    set("module-phrase-status", "module phrase set: bind again with it", "good");
  } else if (o.Refused !== "Replayed") {
    // A stale counter is sealed again by the phone half; anything else stands.
    modulePhraseSent = false;
    set("module-phrase-status", `module phrase ${MODULE_REFUSALS[o.Refused]}`, "bad");
  }
}

async function sendModulePhrase(text: string): Promise<void> {
  if (state.arm?.armed === true) {
    set("module-phrase-status", "module phrase refused: armed", "bad");
    return;
  }
  if (!transport) {
    status("connect first to set the module's phrase");
    return;
  }
  if (!phone) {
    set("module-phrase-status", "enter the module's current phrase above first", "bad");
    return;
  }
  try {
    const frame = phone.setModulePhrase(text);
    modulePhraseSent = true;
    await transport.send(frame);
    set("module-phrase-status", "sent; waiting for the module");
  } catch (e) {
    set("module-phrase-status", e instanceof Error ? e.message : String(e), "bad");
  }
}

function reset(): void {
  if (replayTimer) clearTimeout(replayTimer);
  replayTimer = undefined;
  transport?.close();
  transport = undefined;
  state = initialState();
  alerts = new Alerts();
  decoder = new Decoder();
}

const sink = {
  onBytes,
  onClosed: (why: string) => {
    status(why);
    transport = undefined;
  },
};

async function connect(how: () => Promise<Transport>): Promise<void> {
  reset();
  try {
    status("connecting…");
    transport = await how();
    status(`connected: ${transport.name}`);
    // A phrase entered before connecting is proven now.
    if (phone) await transport.send(phone.hello());
  } catch (e) {
    status(e instanceof Error ? e.message : String(e));
  }
}

function replay(chunks: Chunk[], name: string): void {
  reset();
  status(`replaying ${name}`);
  let i = 0;
  const t0 = performance.now() - (chunks[0]?.t ?? 0);
  const next = (): void => {
    const c = chunks[i];
    if (!c) {
      status(`replayed ${name}`);
      return;
    }
    onBytes(c.bytes);
    i += 1;
    const following = chunks[i];
    replayTimer = setTimeout(next, following ? Math.max(0, following.t - (performance.now() - t0)) : 0);
  };
  next();
}

function download(name: string, text: string, type: string): void {
  const a = document.createElement("a");
  a.href = URL.createObjectURL(new Blob([text], { type }));
  a.download = name;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 10_000);
}

function stamp(): string {
  return new Date().toISOString().replace(/[:.]/g, "-").slice(0, 19);
}

async function main(): Promise<void> {
  await loadWasm();
  decoder = new Decoder();
  horizon = new Horizon($("horizon"));
  buildSettings();
  const wsUrl = `${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws`;
  $("connect-sim").onclick = () => void connect(() => connectWebSocket(wsUrl, sink));
  $("connect-ble").onclick = () => void connect(() => connectBluetooth(sink));
  $("connect-serial").onclick = async () => {
    try {
      usb = await connectSerial(
        (line) => {
          const kv = parseSettingLine(line);
          if (kv) consoleValues.set(kv[0], kv[1]);
          else if (line.trim()) status(`USB: ${line.trim()}`);
        },
        (why) => {
          usb = undefined;
          status(why);
        },
      );
      status("USB console connected");
      await usb.command("list");
    } catch (e) {
      status(e instanceof Error ? e.message : String(e));
    }
  };
  $("phrase-use").onclick = async () => {
    const input = $<HTMLInputElement>("phrase");
    try {
      phone = new Phone(input.value);
      showStanding();
      if (transport) {
        await transport.send(phone.hello());
        status("binding phrase set (in memory only); asking the module to confirm it");
      } else {
        status("binding phrase set (in memory only); the module confirms it once connected");
      }
    } catch (e) {
      phone = undefined;
      showStanding();
      status(e instanceof Error ? e.message : String(e));
    }
    input.value = "";
  };
  $("module-phrase-send").onclick = () => {
    const input = $<HTMLInputElement>("module-phrase");
    const text = input.value;
    input.value = "";
    void sendModulePhrase(text);
  };
  $("settings-read").onclick = () => void usb?.command("list");
  $("settings-save").onclick = () => void usb?.command("save");
  $("settings-filter").oninput = buildSettings;
  $("settings-rows").onclick = (ev) => {
    const id = (ev.target as HTMLElement).dataset.set;
    const row = settings.find((r) => String(r.id) === id);
    const control = document.querySelector<HTMLInputElement | HTMLSelectElement>(`[data-id="${id}"]`);
    const text = control?.value.trim() ?? "";
    if (row && text) void sendSetting(row, Number(text));
  };
  $("mute").onclick = () => {
    speaker.muted = !speaker.muted;
    $("mute").setAttribute("aria-pressed", String(speaker.muted));
    if (speaker.muted) globalThis.speechSynthesis?.cancel();
  };
  $("record").onclick = () => {
    if (recorder) {
      lastLog = recorder.text();
      recorder = undefined;
      $("record").setAttribute("aria-pressed", "false");
      $<HTMLButtonElement>("save-log").disabled = false;
      $<HTMLButtonElement>("export-csv").disabled = false;
    } else {
      recorder = new Recorder(performance.now());
      $("record").setAttribute("aria-pressed", "true");
    }
  };
  $("save-log").onclick = () => lastLog && download(`taulink-${stamp()}.tlog`, lastLog, "text/plain");
  $("export-csv").onclick = () => {
    if (!lastLog) return;
    const fresh = new Decoder();
    for (const [kind, csv] of csvByType(parseLog(lastLog), (b) => fresh.push(b) as Event[])) {
      download(`taulink-${stamp()}-${kind}.csv`, csv, "text/csv");
    }
  };
  $<HTMLInputElement>("open-log").onchange = async (ev) => {
    const file = (ev.target as HTMLInputElement).files?.[0];
    if (!file) return;
    try {
      const text = await file.text();
      lastLog = text;
      $<HTMLButtonElement>("export-csv").disabled = false;
      replay(parseLog(text), file.name);
    } catch (e) {
      status(e instanceof Error ? e.message : String(e));
    }
  };
  setInterval(render, 100);
  if ("serviceWorker" in navigator && location.protocol !== "file:") {
    navigator.serviceWorker.register("./sw.js").catch(() => status("offline use unavailable (no service worker)"));
  }
  // Opened from the simulator: connect straight away.
  if (new URLSearchParams(location.search).has("sim")) $("connect-sim").click();
}

void main();
