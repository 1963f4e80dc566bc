/**
 * The WebAssembly half (telemetry-wasm, built by `cargo xtask wasm` into src/wasm/):
 * loading it, and typed wrappers over its JSON answers.
 */
import init, {
  Decoder as WasmDecoder,
  Phone as WasmPhone,
  encode_setting_change,
  setting_check,
  setting_from_wire,
  setting_to_wire,
  settings_table,
} from "./wasm/telemetry_wasm.js";
import type { Event, ModuleEvent } from "./messages";

export interface SettingRow {
  id: number;
  name: string;
  /** The value's unit ("°/s", "µs"), "" for a pure number. */
  unit: string;
  /** What the setting does, in one line (the schema's doc). */
  doc: string;
  kind: "real" | "whole" | "choice";
  min?: number;
  max?: number;
  choices?: string[];
  default: number;
}

/** Loads the module (once; `source` lets tests hand in the bytes). */
export async function loadWasm(source?: BufferSource): Promise<void> {
  await init(source === undefined ? undefined : { module_or_path: source });
}

/** A stream decoder: bytes in any chunking → events. */
export class Decoder {
  private readonly inner = new WasmDecoder();

  push(bytes: Uint8Array): Event[] {
    return JSON.parse(this.inner.push(bytes)) as Event[];
  }

  /** The raw JSON (for the byte-identity test against the Rust reader). */
  pushJson(bytes: Uint8Array): string {
    return this.inner.push(bytes);
  }

  get dropped(): number {
    return this.inner.dropped();
  }
}

export function settingsTable(): SettingRow[] {
  return JSON.parse(settings_table()) as SettingRow[];
}

/** The frame that asks the flight side to set `id` to `value`, or undefined if it would refuse. */
export function settingChangeFrame(id: number, value: number): Uint8Array | undefined {
  const wire = setting_to_wire(id, value);
  return wire === undefined ? undefined : encode_setting_change(id, wire);
}

/** The wire value of `value` for setting `id`, or why the flight side would refuse it. */
export function checkSetting(id: number, value: number): { wire: number } | { refused: string } {
  try {
    return { wire: setting_check(id, value) };
  } catch (e) {
    return { refused: e instanceof Error ? e.message : String(e) };
  }
}

export function settingValue(id: number, wire: number): number | undefined {
  return setting_from_wire(id, wire);
}

/**
 * The phone's half (Rust, telemetry::module_record and change_auth via telemetry-wasm): the
 * binding phrase in memory only, proven to the module with CPace (spec §12.5); the module's
 * grant carries the change key the flight side checks changes with. Throws for a phrase the
 * phrase rule refuses (12+ characters, 6 different, no famous example).
 */
export class Phone {
  private readonly inner: WasmPhone;

  constructor(phrase: string) {
    this.inner = new WasmPhone(phrase);
  }

  /** The record asking the module for its challenge. */
  hello(): Uint8Array {
    return this.inner.hello();
  }

  /** "unknown", "granted", "granted-no-link" or "refused:REASON". */
  get standing(): string {
    return this.inner.standing();
  }

  /** A record from the module: the record to send next, or undefined. */
  onModuleRecord(event: ModuleEvent): Uint8Array | undefined {
    const random = crypto.getRandomValues(new Uint8Array(32));
    const frame = this.inner.on_module_record(JSON.stringify(event), random);
    return frame.length ? frame : undefined;
  }

  /** The record setting the module's phrase (or the Hello that comes first). Throws for a phrase the rule refuses. */
  setModulePhrase(newPhrase: string): Uint8Array {
    return this.inner.set_module_phrase(newPhrase);
  }

  /** The signed change frame of `id` to the wire value `wire` (from `checkSetting`); undefined until the module granted the change key. */
  signChange(id: number, wire: number): Uint8Array | undefined {
    const frame = this.inner.sign_change(id, wire);
    return frame.length ? frame : undefined;
  }

  /** A refusal from the flight side: the frame to send again, or undefined (the refusal stands). */
  onRefused(refused: unknown): Uint8Array | undefined {
    const frame = this.inner.on_refused(JSON.stringify(refused));
    return frame.length ? frame : undefined;
  }
}
