/**
 * The WebAssembly half (telemetry-wasm, built by `cargo xtask wasm` into src/wasm/):
 * loading it, and typed wrappers over its JSON answers.
 */
import init, {
  Decoder as WasmDecoder,
  Phone as WasmPhone,
  encode_setting_change,
  phrase_fingerprint,
  propose_module_phrase,
  setting_check,
  setting_from_wire,
  setting_to_wire,
  settings_table,
} from "./wasm/telemetry_wasm.js";
import type { Event, KeyAnswer } from "./messages";

export interface SettingRow {
  id: number;
  name: string;
  /** The value's unit ("°/s", "µs"), "" for a pure number. */
  unit: string;
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

  /** The signed change frame of `id` to the wire value `wire` (from `checkSetting`). */
  signChange(id: number, wire: number): Uint8Array {
    return this.inner.sign_change(id, wire);
  }

  /**
   * The record setting the module's phrase to `newPhrase`, signed with this phrase (which must
   * be the module's current one): the module takes it at once. Throws for an unusable phrase.
   */
  signModulePhrase(newPhrase: string): Uint8Array {
    return this.inner.sign_module_phrase(newPhrase);
  }

  /** The module's answer: the record to send again, or undefined (the answer stands). */
  onModuleAnswer(answer: KeyAnswer): Uint8Array | undefined {
    const frame = this.inner.on_module_answer(JSON.stringify(answer));
    return frame.length ? frame : undefined;
  }

  /** A refusal from the flight side: the frame to send again, or undefined (the refusal stands). */
  onRefused(refused: unknown): Uint8Array | undefined {
    const frame = this.inner.on_refused(JSON.stringify(refused));
    return frame.length ? frame : undefined;
  }
}

/**
 * The record proposing `phrase` as the module's phrase: the module takes it only once the
 * pilot confirms on the radio (Phone Phrase). Throws for an empty or unusable phrase.
 */
export function moduleProposalFrame(phrase: string): Uint8Array {
  return propose_module_phrase(phrase);
}

/** The fingerprint (`1a2b-3c4d`) of `phrase`'s key. Throws for an empty or unusable phrase. */
export function phraseFingerprint(phrase: string): string {
  return phrase_fingerprint(phrase);
}

/** A 32-bit key fingerprint as the radio and the consoles show it. */
export function fingerprintText(f: number): string {
  const hex = (n: number) => n.toString(16).padStart(4, "0");
  return `${hex(f >>> 16)}-${hex(f & 0xffff)}`;
}
