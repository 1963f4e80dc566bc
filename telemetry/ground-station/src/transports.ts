/**
 * Where the stream comes from. Each transport hands received bytes to `onBytes` as they
 * arrive and sends frames the app made (setting changes):
 * - Web Bluetooth to the module's HM-10 (service 0xFFE0, characteristic 0xFFE1): the relay
 *   framing, COBS + 0x00 per record, which is the link frame byte for byte; writes go in
 *   20-byte pieces (one BLE 4.0 packet each), the relay reassembles at the 0x00.
 * - WebSocket to the simulator (`taulink-sim --serve`): the same bytes in binary messages.
 * - Web Serial to the flight controller's USB console: a text console (`list`, `set`,
 *   `save`), so it is a separate line-based transport.
 */

export interface Transport {
  readonly name: string;
  send(bytes: Uint8Array): Promise<void>;
  close(): void;
}

export interface Sink {
  onBytes(bytes: Uint8Array): void;
  onClosed(reason: string): void;
}

export const HM10_SERVICE = 0xffe0;
export const HM10_CHARACTERISTIC = 0xffe1;
/** Bytes per BLE 4.0 write. */
export const BLE_CHUNK = 20;

/** Splits `bytes` into writes of at most `size` bytes. */
export function pieces(bytes: Uint8Array, size: number): Uint8Array[] {
  const out: Uint8Array[] = [];
  for (let i = 0; i < bytes.length; i += size) out.push(bytes.subarray(i, i + size));
  return out;
}

export function connectWebSocket(url: string, sink: Sink): Promise<Transport> {
  return new Promise((resolve, reject) => {
    const ws = new WebSocket(url);
    ws.binaryType = "arraybuffer";
    let open = false;
    ws.onopen = () => {
      open = true;
      resolve({
        name: "simulator",
        send: async (bytes) => ws.send(bytes),
        close: () => ws.close(),
      });
    };
    ws.onmessage = (m) => {
      if (m.data instanceof ArrayBuffer) sink.onBytes(new Uint8Array(m.data));
    };
    ws.onerror = () => {
      if (!open) reject(new Error(`cannot connect to ${url}`));
    };
    ws.onclose = () => {
      if (open) sink.onClosed("simulator closed the connection");
    };
  });
}

export async function connectBluetooth(sink: Sink): Promise<Transport> {
  const bt = navigator.bluetooth;
  if (!bt) throw new Error("this browser has no Web Bluetooth");
  const device = await bt.requestDevice({ filters: [{ services: [HM10_SERVICE] }] });
  const server = await device.gatt?.connect();
  if (!server) throw new Error("no GATT server on that device");
  const ch = await (await server.getPrimaryService(HM10_SERVICE)).getCharacteristic(HM10_CHARACTERISTIC);
  ch.addEventListener("characteristicvaluechanged", () => {
    const v = ch.value;
    if (v) sink.onBytes(new Uint8Array(v.buffer.slice(v.byteOffset, v.byteOffset + v.byteLength)));
  });
  device.addEventListener("gattserverdisconnected", () => sink.onClosed("Bluetooth disconnected"));
  await ch.startNotifications();
  return {
    name: `Bluetooth ${device.name ?? "HM-10"}`,
    send: async (bytes) => {
      for (const p of pieces(bytes, BLE_CHUNK)) await ch.writeValueWithoutResponse(new Uint8Array(p));
    },
    close: () => server.disconnect(),
  };
}

/** The flight controller's USB console (VID/PID 0x20A0/0x415B): lines in, commands out. */
export interface Console {
  command(line: string): Promise<void>;
  close(): void;
}

export async function connectSerial(onLine: (line: string) => void, onClosed: (why: string) => void): Promise<Console> {
  const serial = navigator.serial;
  if (!serial) throw new Error("this browser has no Web Serial");
  const port = await serial.requestPort({ filters: [{ usbVendorId: 0x20a0, usbProductId: 0x415b }] });
  await port.open({ baudRate: 115200 });
  const reader = port.readable?.getReader();
  const writer = port.writable?.getWriter();
  if (!reader || !writer) throw new Error("the port cannot be read and written");
  const text = new TextDecoder();
  void (async () => {
    let pending = "";
    try {
      for (;;) {
        const { value, done } = await reader.read();
        if (done) break;
        pending += text.decode(value, { stream: true });
        const lines = pending.split(/\r?\n/);
        pending = lines.pop() ?? "";
        // Bounded: a console line is short; a runaway one is cut.
        if (pending.length > 4096) pending = "";
        lines.forEach(onLine);
      }
    } finally {
      onClosed("USB console closed");
    }
  })();
  const enc = new TextEncoder();
  return {
    command: (line) => writer.write(enc.encode(`${line}\r\n`)),
    close: () => {
      void reader.cancel();
      void port.close();
    },
  };
}

/** Parses a console `list`/`get` answer line `name = value`. */
export function parseSettingLine(line: string): [string, string] | undefined {
  const m = /^([a-z0-9_.]+) = (\S+)$/.exec(line.trim());
  return m && m[1] !== undefined && m[2] !== undefined ? [m[1], m[2]] : undefined;
}
