/**
 * The telemetry messages as the WebAssembly decoder renders them: serde's JSON of
 * `telemetry::messages::Message` (externally tagged), and "Dropped" for a frame that was
 * corrupt, oversize or unknown. These types only describe that JSON; decoding is Rust.
 */

export interface Attitude { roll_cdeg: number; pitch_cdeg: number; yaw_cdeg: number }
export interface Battery { voltage_mv: number; current_ca: number; used_mah: number; remaining_percent: number }
export interface LinkStats {
  uplink_rssi_dbm: number; uplink_lq: number; downlink_rssi_dbm: number; downlink_lq: number;
  rate_mode: number; received: number; missed: number; failsafes: number;
}
/** `telemetry::messages::FlightMode`: what the controller flies, as the flight side reports it. */
export type FlightMode =
  | "RatePid" | "RateLqg" | "Attitude" | "Horizon" | "SystemId" | "AltitudeHold" | "PositionHold" | "Loiter";
export interface ArmState { armed: boolean; failsafe: boolean; arming_blockers: number }
export type GpsFix = "None" | "Fix2d" | "Fix3d";
export interface Gps {
  latitude_e7: number; longitude_e7: number; altitude_cm: number; ground_speed_cm_s: number;
  course_cdeg: number; satellites: number; fix: GpsFix;
}
/** The flight side's home (first usable fix); `set` false: the position means nothing. */
export interface Home { latitude_e7: number; longitude_e7: number; altitude_cm: number; set: boolean }
export type Axis = "Roll" | "Pitch" | "Yaw";
export interface SysIdResult { axis: Axis; beta1: number; beta2: number; tau_s: number; noise: number }
export interface SettingChange { id: number; value: number }
export interface SignedChange { change: SettingChange; counter: number; tag: number[] }
export type RefuseReason = "Armed" | "NotAuthenticated" | "Replayed" | "NoPhrase" | "Invalid";
export interface ChangeRefused { id: number; reason: RefuseReason; session: number; counter: number }

/** Tag failures at the flight side (spec §12.2) and whether they run above noise. */
export interface LinkSecurity { tag_failures: number; alert: boolean }

export type Message =
  | { Attitude: Attitude }
  | { Battery: Battery }
  | { LinkStats: LinkStats }
  /** An older flight side's mode (retired wire number): its numbers meant other modes; ignored. */
  | { RetiredFlightMode: number }
  | { ArmState: ArmState }
  | { Gps: Gps }
  | { SysIdResult: SysIdResult }
  | { SettingChange: SettingChange }
  | { SignedChange: SignedChange }
  | { ChangeRefused: ChangeRefused }
  | { Home: Home }
  | { FlightMode: FlightMode }
  | { LinkSecurity: LinkSecurity };

/** Why the module refused a phone's record (`telemetry::module_record::Refusal`). */
export type ModuleRefusal = "Armed" | "NotAuthenticated" | "Replayed" | "NoPhrase" | "NoSession" | "Locked" | "Invalid";
export type ModuleOutcome = "Applied" | { Refused: ModuleRefusal };
/** The module's answer to a phone's record. */
export interface ModuleAnswer { outcome: ModuleOutcome; counter: number }
/** Both ends' tag failures as the module reports them to the phone. */
export interface ModuleLinkSecurity { tag_failures_down: number; tag_failures_up: number; alert: boolean }
/** Records the module itself sends the phone (`telemetry::module_record::ModuleRecord`); the exchange's own ones are the phone half's to read. */
export type ModuleEvent =
  | { Challenge: unknown }
  | { Granted: unknown }
  | { Answer: ModuleAnswer }
  | { LinkSecurity: ModuleLinkSecurity };

export type Event = Message | ModuleEvent | "Dropped";

/** The variant name of a message ("Attitude", "Battery", ...). */
export function kindOf(m: Exclude<Event, "Dropped">): string {
  return Object.keys(m)[0] ?? "";
}

/** Flight mode names as a pilot says them. */
export const MODE_NAMES: Record<FlightMode, string> = {
  RatePid: "Rate PID",
  RateLqg: "Rate LQG",
  Attitude: "Attitude",
  Horizon: "Horizon",
  SystemId: "System identification",
  AltitudeHold: "Altitude hold",
  PositionHold: "Position hold",
  Loiter: "Loiter",
};

/** `ArmState.arming_blockers` bits (flight_core::report::blocker_bit). */
export const ARMING_BLOCKERS: [number, string][] = [
  [1, "link down"],
  [2, "throttle not low"],
  [4, "sensors unhealthy"],
  [8, "gains not ready"],
];

export function blockerNames(bits: number): string[] {
  return ARMING_BLOCKERS.filter(([bit]) => (bits & bit) !== 0).map(([, name]) => name);
}

/** Rate mode wire codes (`telemetry::link::RateMode::code`). */
export const RATE_MODES = ["L50", "M100", "F250", "F500"];
