/** How values read on screen (and to a screen reader): units always, fixed decimals. */
import { headingDeg } from "./views";

export const volts = (mv: number): string => `${(mv / 1000).toFixed(2)} V`;
export const amps = (ca: number): string => `${(ca / 100).toFixed(1)} A`;
export const percent = (p: number): string => `${p} %`;
export const dbm = (d: number): string => `${d} dBm`;
export const degrees = (cdeg: number): string => `${(cdeg / 100).toFixed(1)}°`;
export const heading = (yawCdeg: number): string => `${Math.round(headingDeg(yawCdeg)) % 360}°`.padStart(4, "0");
export const yesNo = (b: boolean): string => (b ? "Yes" : "No");
export const latLon = (latE7: number, lonE7: number): string =>
  `${(latE7 / 1e7).toFixed(6)}, ${(lonE7 / 1e7).toFixed(6)}`;
/** A setting's real number (an f32 widened) as the console prints it: 0.3, not 0.30000001192092896. */
export const real = (v: number): string => String(Number(v.toPrecision(7)));
