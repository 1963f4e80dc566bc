/**
 * The WebAssembly half (telemetry-wasm, built by scripts/build-wasm.sh into src/wasm/):
 * loading it, and typed wrappers over its JSON answers.
 */
import init, {
  Decoder as WasmDecoder,
  Phone as WasmPhone,
  encode_setting_change,
  setting_from_wire,
  setting_to_wire,
  settings_table,
} from "./wasm/telemetry_wasm.js";
import type { Event } from "./messages";

export interface SettingRow {
  id: number;
  name: string;
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

export function settingValue(id: number, wire: number): number | undefined {
  return setting_from_wire(id, wire);
}

/**
 * The phone's signing half (Rust, telemetry::change_auth via telemetry-wasm): holds the key
 * derived from the binding phrase in memory only. Throws for an empty or unusable phrase.
 */
export class Phone {
  private readonly inner: WasmPhone;

  constructor(phrase: string) {
    this.inner = new WasmPhone(phrase);
  }

  get fingerprint(): string {
    return this.inner.fingerprint();
  }

  /** The signed change frame of `id` to `value`, or undefined if the flight side would refuse the value. */
  signChange(id: number, value: number): Uint8Array | undefined {
    const wire = setting_to_wire(id, value);
    return wire === undefined ? undefined : this.inner.sign_change(id, wire);
  }

  /** A refusal from the flight side: the frame to send again, or undefined (the refusal stands). */
  onRefused(refused: unknown): Uint8Array | undefined {
    const frame = this.inner.on_refused(JSON.stringify(refused));
    return frame.length ? frame : undefined;
  }
}
