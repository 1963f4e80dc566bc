/**
 * What the ground station says aloud, and how often: battery warning / critical (per cell,
 * at the flight side's thresholds), flight-mode changes, arm / disarm, failsafe, and the
 * telemetry link lost / regained. Only changes are spoken, never the first value seen, and
 * a battery level repeats at most every `BATTERY_REPEAT_MS` while it lasts — chatter a pilot
 * keeps on. Pure: the caller hands in states and the time and speaks the phrases.
 */
import { MODE_NAMES, blockerNames } from "./messages";
import type { State } from "./model";

/** flight_core::battery defaults: warning 3.5 V, critical 3.3 V per cell. */
export const CELL_WARNING_MV = 3500;
export const CELL_CRITICAL_MV = 3300;
/** Highest charged cell (HV LiPo), to count cells from the first reading. */
export const CELL_MAX_MV = 4350;
/** A level is left only this far above its threshold (no flapping on sag). */
export const CELL_HYSTERESIS_MV = 100;
export const BATTERY_REPEAT_MS = 30_000;
/** Silence after which the telemetry link counts as lost. */
export const LINK_LOST_MS = 2_000;

export type BatteryLevel = "ok" | "warning" | "critical";

export class Alerts {
  private cells?: number;
  private level: BatteryLevel = "ok";
  private levelSpokenMs = -Infinity;
  private mode?: string;
  private armed?: boolean;
  private failsafe?: boolean;
  private linkUp = false;

  /** Cell count (from the first battery reading above 0.5 V). */
  get cellCount(): number | undefined {
    return this.cells;
  }

  get batteryLevel(): BatteryLevel {
    return this.level;
  }

  /** Phrases to speak for the state `s` at `nowMs`. */
  update(s: State, nowMs: number): string[] {
    const say: string[] = [];
    const fresh = s.lastMessageMs !== undefined && nowMs - s.lastMessageMs < LINK_LOST_MS;
    if (fresh !== this.linkUp) {
      if (fresh && s.messages > 0 && this.mode !== undefined) say.push("Telemetry regained");
      if (!fresh && this.linkUp) say.push("Telemetry lost");
      this.linkUp = fresh;
    }
    if (s.mode !== undefined && s.mode !== this.mode) {
      if (this.mode !== undefined) say.push(`Flight mode ${MODE_NAMES[s.mode]}`);
      this.mode = s.mode;
    }
    if (s.arm) {
      if (this.armed !== undefined && s.arm.armed !== this.armed) {
        say.push(s.arm.armed ? "Armed" : "Disarmed");
      }
      if (this.failsafe !== undefined && s.arm.failsafe !== this.failsafe) {
        say.push(s.arm.failsafe ? "Failsafe" : "Failsafe cleared");
      }
      this.armed = s.arm.armed;
      this.failsafe = s.arm.failsafe;
    }
    if (s.battery) say.push(...this.battery(s.battery.voltage_mv, nowMs));
    return say;
  }

  private battery(mv: number, nowMs: number): string[] {
    if (this.cells === undefined) {
      if (mv <= 500) return [];
      this.cells = Math.ceil(mv / CELL_MAX_MV);
    }
    const cell = mv / this.cells;
    let level: BatteryLevel;
    if (cell < CELL_CRITICAL_MV) level = "critical";
    else if (this.level === "critical" && cell < CELL_CRITICAL_MV + CELL_HYSTERESIS_MV) level = "critical";
    else if (cell < CELL_WARNING_MV) level = "warning";
    else if (this.level !== "ok" && cell < CELL_WARNING_MV + CELL_HYSTERESIS_MV) level = "warning";
    else level = "ok";
    const changed = level !== this.level;
    this.level = level;
    if (level === "ok") return [];
    if (!changed && nowMs - this.levelSpokenMs < BATTERY_REPEAT_MS) return [];
    this.levelSpokenMs = nowMs;
    const volts = (mv / 1000).toFixed(1);
    return [level === "critical" ? `Battery critical, ${volts} volts` : `Battery low, ${volts} volts`];
  }
}

/** The arm / failsafe line shown on screen, with the reason arming is refused. */
export function armText(s: State): string {
  if (!s.arm) return "—";
  if (s.arm.failsafe) return s.arm.armed ? "Armed, failsafe" : "Failsafe";
  if (s.arm.armed) return "Armed";
  const why = blockerNames(s.arm.arming_blockers);
  return why.length > 0 ? `Disarmed (${why.join(", ")})` : "Disarmed, ready";
}

/** Speaks phrases with the Web Speech API; mute drops them (nothing queued for later). */
export class Speaker {
  muted = false;
  constructor(private readonly synth: SpeechSynthesis | undefined = globalThis.speechSynthesis) {}

  speak(phrases: string[]): void {
    if (this.muted || !this.synth) return;
    for (const p of phrases) this.synth.speak(new SpeechSynthesisUtterance(p));
  }
}
