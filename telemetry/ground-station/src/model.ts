/**
 * The ground station's picture of the aircraft: the latest value of every message, the
 * bounded histories behind the strip charts and the GPS track, and the settings the flight
 * side reported. Pure: `apply` folds one decoded event in at a given time.
 */
import type { ArmState, Attitude, Axis, Battery, ChangeRefused, Event, FlightMode, Gps, Home, LinkStats, SysIdResult } from "./messages";

/** Tag failures (spec §12.2): the module's count (when it reported), the flight side's, and the alert. */
export interface TagFailures { down?: number; up: number; alert: boolean }

/** Strip charts show this much history. */
export const HISTORY_MS = 5 * 60_000;
/** Track points kept (at GPS rates, hours of flight thinned by distance). */
export const TRACK_POINTS = 5000;
/** A new track point only this far (metres) from the last one. */
export const TRACK_STEP_M = 1;

export interface LinkSample { t: number; upLq: number; dnLq: number; upRssi: number; dnRssi: number }
export interface TrackPoint { lat: number; lon: number }

export interface State {
  attitude?: Attitude;
  battery?: Battery;
  link?: LinkStats;
  mode?: FlightMode;
  arm?: ArmState;
  gps?: Gps;
  /** The flight side's home, once it reported one set. */
  home?: Home;
  /** Tag failures, once either end reported them. */
  tags?: TagFailures;
  sysid: Partial<Record<Axis, SysIdResult>>;
  /** Setting id → wire value the flight side reported. */
  settings: Map<number, number>;
  /** The flight side's last refusal of a change from this page (cleared by an applied one). */
  refused?: ChangeRefused;
  linkHistory: LinkSample[];
  track: TrackPoint[];
  /** Time of the last message (ms), for "telemetry lost". */
  lastMessageMs?: number;
  messages: number;
  dropped: number;
}

export function initialState(): State {
  return { sysid: {}, settings: new Map(), linkHistory: [], track: [], messages: 0, dropped: 0 };
}

/** Metres between two points (equirectangular; exact enough at track scales). */
export function distanceM(a: TrackPoint, b: TrackPoint): number {
  const r = 6_371_000;
  const rad = Math.PI / 180;
  const x = (b.lon - a.lon) * rad * Math.cos(((a.lat + b.lat) / 2) * rad);
  const y = (b.lat - a.lat) * rad;
  return Math.hypot(x, y) * r;
}

/** Folds `event`, received at `tMs`, into `s` (mutated and returned). */
export function apply(s: State, event: Event, tMs: number): State {
  if (event === "Dropped") {
    s.dropped += 1;
    return s;
  }
  s.messages += 1;
  s.lastMessageMs = tMs;
  if ("Attitude" in event) s.attitude = event.Attitude;
  else if ("Battery" in event) s.battery = event.Battery;
  else if ("FlightMode" in event) s.mode = event.FlightMode;
  else if ("ArmState" in event) s.arm = event.ArmState;
  else if ("SysIdResult" in event) s.sysid[event.SysIdResult.axis] = event.SysIdResult;
  else if ("SettingChange" in event) {
    s.settings.set(event.SettingChange.id, event.SettingChange.value);
    if (s.refused?.id === event.SettingChange.id) s.refused = undefined;
  } else if ("ChangeRefused" in event) s.refused = event.ChangeRefused;
  else if ("LinkStats" in event) {
    const l = event.LinkStats;
    s.link = l;
    s.linkHistory.push({ t: tMs, upLq: l.uplink_lq, dnLq: l.downlink_lq, upRssi: l.uplink_rssi_dbm, dnRssi: l.downlink_rssi_dbm });
    const oldest = tMs - HISTORY_MS;
    let drop = 0;
    while (drop < s.linkHistory.length && (s.linkHistory[drop]?.t ?? tMs) < oldest) drop += 1;
    if (drop > 0) s.linkHistory.splice(0, drop);
  } else if ("LinkSecurity" in event) {
    const l = event.LinkSecurity;
    // The module's record carries both ends' counts; the flight side's message its own.
    s.tags = "tag_failures_down" in l
      ? { down: l.tag_failures_down, up: l.tag_failures_up, alert: l.alert }
      : { down: s.tags?.down, up: l.tag_failures, alert: l.alert };
  } else if ("Home" in event) {
    s.home = event.Home.set ? event.Home : undefined;
  } else if ("Gps" in event) {
    const g = event.Gps;
    s.gps = g;
    if (g.fix !== "None") {
      const p = { lat: g.latitude_e7 / 1e7, lon: g.longitude_e7 / 1e7 };
      const last = s.track[s.track.length - 1];
      if (!last || distanceM(last, p) >= TRACK_STEP_M) {
        s.track.push(p);
        if (s.track.length > TRACK_POINTS) s.track.splice(0, s.track.length - TRACK_POINTS);
      }
    }
  }
  return s;
}
