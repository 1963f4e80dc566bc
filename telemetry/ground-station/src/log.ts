/**
 * Session logs: the raw stream as received, with receive times, so a replay runs the same
 * decoder over the same bytes in the same chunks. File format (text, one chunk a line):
 *
 *     # taulink-gcs log 1
 *     <ms since the recording started> <chunk as hex>
 *
 * Also the CSV export: the log decoded again, one table per message type, a row per
 * message with its receive time.
 */
import type { Event } from "./messages";
import { kindOf } from "./messages";

export const LOG_HEADER = "# taulink-gcs log 1";
/** A recording stops growing here (≈ hours of telemetry at BLE rates). */
export const LOG_MAX_BYTES = 32 * 1024 * 1024;

export interface Chunk { t: number; bytes: Uint8Array }

export function toHex(bytes: Uint8Array): string {
  let s = "";
  for (const b of bytes) s += b.toString(16).padStart(2, "0");
  return s;
}

export function fromHex(hex: string): Uint8Array | undefined {
  if (hex.length % 2 !== 0 || !/^[0-9a-fA-F]*$/.test(hex)) return undefined;
  const out = new Uint8Array(hex.length / 2);
  for (let i = 0; i < out.length; i++) out[i] = parseInt(hex.slice(2 * i, 2 * i + 2), 16);
  return out;
}

/** Records chunks with their time since `start`; bounded by LOG_MAX_BYTES. */
export class Recorder {
  private lines: string[] = [LOG_HEADER];
  private size = 0;
  truncated = false;
  constructor(private readonly startMs: number) {}

  add(nowMs: number, bytes: Uint8Array): void {
    if (this.size + bytes.length > LOG_MAX_BYTES) {
      this.truncated = true;
      return;
    }
    this.size += bytes.length;
    this.lines.push(`${Math.round(nowMs - this.startMs)} ${toHex(bytes)}`);
  }

  get chunks(): number {
    return this.lines.length - 1;
  }

  text(): string {
    return this.lines.join("\n") + "\n";
  }
}

/** Parses a log file; throws on anything that is not one. */
export function parseLog(text: string): Chunk[] {
  const lines = text.split(/\r?\n/);
  if (lines[0]?.trim() !== LOG_HEADER) throw new Error("not a TauLink ground station log");
  const out: Chunk[] = [];
  lines.slice(1).forEach((line, i) => {
    if (line.trim() === "") return;
    const [t, hex, extra] = line.trim().split(/\s+/);
    const bytes = fromHex(hex ?? "");
    const time = Number(t);
    if (extra !== undefined || bytes === undefined || !Number.isFinite(time)) {
      throw new Error(`log line ${i + 2} is damaged`);
    }
    out.push({ t: time, bytes });
  });
  return out;
}

/** Flattens a message's fields: `{Battery:{voltage_mv:1}}` → `[["voltage_mv", 1]]`. */
function fields(m: Exclude<Event, "Dropped">): [string, string][] {
  const body = (m as Record<string, unknown>)[kindOf(m)];
  if (typeof body !== "object" || body === null) return [["value", String(body)]];
  return Object.entries(body as Record<string, unknown>).map(([k, v]) => [k, String(v)]);
}

/**
 * One CSV text per message type, from a log's chunks decoded by `decode` (a fresh
 * decoder's `push`). Columns: t_ms, then the message's fields in the decoder's order.
 */
export function csvByType(chunks: Chunk[], decode: (bytes: Uint8Array) => Event[]): Map<string, string> {
  const tables = new Map<string, string[]>();
  for (const { t, bytes } of chunks) {
    for (const e of decode(bytes)) {
      if (e === "Dropped") continue;
      const kind = kindOf(e);
      const f = fields(e);
      let rows = tables.get(kind);
      if (!rows) {
        rows = [["t_ms", ...f.map(([k]) => k)].join(",")];
        tables.set(kind, rows);
      }
      rows.push([String(t), ...f.map(([, v]) => v)].join(","));
    }
  }
  return new Map([...tables].map(([k, rows]) => [k, rows.join("\n") + "\n"]));
}
