/**
 * Drawing: the artificial horizon with its heading tape (SVG), the link strip charts and
 * the GPS track (canvas, no map tiles). The projections are pure functions, tested.
 */
import type { LinkSample, TrackPoint } from "./model";
import { HISTORY_MS } from "./model";

const SVG = "http://www.w3.org/2000/svg";

/** The horizon's transform for roll and pitch (degrees): pitch moves it 2 px per degree. */
export function horizonTransform(rollDeg: number, pitchDeg: number): string {
  return `rotate(${(-rollDeg).toFixed(1)} 100 100) translate(0 ${(pitchDeg * 2).toFixed(1)})`;
}

/** Heading in 0..360 from centidegrees in −18000..18000. */
export function headingDeg(yawCdeg: number): number {
  return (((yawCdeg / 100) % 360) + 360) % 360;
}

export class Horizon {
  private readonly world: SVGGElement;
  private readonly tape: SVGGElement;

  constructor(host: HTMLElement) {
    host.innerHTML = `
      <svg viewBox="0 0 200 200" role="img" aria-label="Artificial horizon">
        <defs><clipPath id="hz-clip"><circle cx="100" cy="100" r="92"/></clipPath></defs>
        <g clip-path="url(#hz-clip)">
          <g class="hz-world">
            <rect x="-200" y="-300" width="600" height="400" fill="#3d7ab8"/>
            <rect x="-200" y="100" width="600" height="400" fill="#8a5a2b"/>
            <line x1="-200" y1="100" x2="400" y2="100" stroke="#fff" stroke-width="1.5"/>
            ${[-20, -10, 10, 20].map((p) => `<line x1="${p % 20 ? 85 : 75}" x2="${p % 20 ? 115 : 125}" y1="${100 - p * 2}" y2="${100 - p * 2}" stroke="#fff" stroke-width="1"/>`).join("")}
          </g>
        </g>
        <circle cx="100" cy="100" r="92" fill="none" stroke="#222" stroke-width="4"/>
        <path d="M60 100 h25 l7 8 M140 100 h-25 l-7 8" stroke="#ffcc00" stroke-width="4" fill="none"/>
        <circle cx="100" cy="100" r="3" fill="#ffcc00"/>
      </svg>
      <svg viewBox="0 0 200 28" class="tape" role="img" aria-label="Compass strip">
        <rect width="200" height="28" fill="#111"/>
        <g class="hz-tape"></g>
        <path d="M100 0 l-5 7 h10z" fill="#ffcc00"/>
      </svg>`;
    this.world = host.querySelector(".hz-world") as SVGGElement;
    this.tape = host.querySelector(".hz-tape") as SVGGElement;
    for (let d = -360; d <= 720; d += 15) {
      const x = 100 + d * 2;
      const t = document.createElementNS(SVG, "text");
      t.setAttribute("x", String(x));
      t.setAttribute("y", "21");
      t.setAttribute("text-anchor", "middle");
      t.setAttribute("fill", "#ddd");
      t.setAttribute("font-size", d % 90 === 0 ? "11" : "8");
      const n = ((d % 360) + 360) % 360;
      t.textContent = d % 90 === 0 ? (["N", "E", "S", "W"][n / 90] ?? "") : d % 45 === 0 ? String(n) : "|";
      this.tape.appendChild(t);
    }
  }

  update(rollDeg: number, pitchDeg: number, heading: number): void {
    this.world.setAttribute("transform", horizonTransform(rollDeg, pitchDeg));
    this.tape.setAttribute("transform", `translate(${(-heading * 2).toFixed(1)} 0)`);
  }
}

/** x of time `t` on a chart `width` wide ending at `now` and spanning HISTORY_MS. */
export function chartX(t: number, now: number, width: number): number {
  return width - ((now - t) / HISTORY_MS) * width;
}

function sizedContext(canvas: HTMLCanvasElement): CanvasRenderingContext2D | null {
  const ratio = globalThis.devicePixelRatio || 1;
  const w = canvas.clientWidth || 300;
  const h = canvas.clientHeight || 120;
  if (canvas.width !== Math.round(w * ratio)) canvas.width = Math.round(w * ratio);
  if (canvas.height !== Math.round(h * ratio)) canvas.height = Math.round(h * ratio);
  const ctx = canvas.getContext("2d");
  ctx?.setTransform(ratio, 0, 0, ratio, 0, 0);
  return ctx;
}

/** Strip chart of two series of the link history over the last HISTORY_MS. */
export function drawStrip(
  canvas: HTMLCanvasElement,
  history: LinkSample[],
  now: number,
  series: [(s: LinkSample) => number, string][],
  range: [number, number],
  label: string,
): void {
  const ctx = sizedContext(canvas);
  if (!ctx) return;
  const w = canvas.clientWidth || 300;
  const h = canvas.clientHeight || 120;
  ctx.clearRect(0, 0, w, h);
  ctx.strokeStyle = "#333";
  ctx.lineWidth = 1;
  for (let i = 1; i < 4; i++) {
    ctx.beginPath();
    ctx.moveTo(0, (h * i) / 4);
    ctx.lineTo(w, (h * i) / 4);
    ctx.stroke();
  }
  const [lo, hi] = range;
  ctx.fillStyle = "#9aa0a6";
  ctx.font = "11px system-ui, sans-serif";
  ctx.fillText(`${label}  ${hi} … ${lo}, last ${HISTORY_MS / 60_000} min`, 6, 14);
  for (const [get, colour] of series) {
    ctx.strokeStyle = colour;
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    history.forEach((s, i) => {
      const x = chartX(s.t, now, w);
      // 3 px margins keep the full-scale line (100 % LQ) visible.
      const y = h - 3 - ((Math.min(hi, Math.max(lo, get(s))) - lo) / (hi - lo)) * (h - 6);
      if (i === 0) ctx.moveTo(x, y);
      else ctx.lineTo(x, y);
    });
    ctx.stroke();
  }
}

/** Local east/north metres of `p` from `origin`. */
export function localM(origin: TrackPoint, p: TrackPoint): [number, number] {
  const r = 6_371_000;
  const rad = Math.PI / 180;
  return [(p.lon - origin.lon) * rad * Math.cos(origin.lat * rad) * r, (p.lat - origin.lat) * rad * r];
}

/** Scale (px per metre) and centre that fit every point in `w`×`h` with a margin. */
export function fitTrack(track: TrackPoint[], w: number, h: number): { scale: number; cx: number; cy: number } {
  const origin = track[0];
  if (!origin) return { scale: 1, cx: 0, cy: 0 };
  let [minX, maxX, minY, maxY] = [0, 0, 0, 0];
  for (const p of track) {
    const [x, y] = localM(origin, p);
    minX = Math.min(minX, x);
    maxX = Math.max(maxX, x);
    minY = Math.min(minY, y);
    maxY = Math.max(maxY, y);
  }
  const span = Math.max(maxX - minX, maxY - minY, 20);
  return { scale: (Math.min(w, h) - 20) / span, cx: (minX + maxX) / 2, cy: (minY + maxY) / 2 };
}

export function drawTrack(canvas: HTMLCanvasElement, track: TrackPoint[]): void {
  const ctx = sizedContext(canvas);
  if (!ctx) return;
  const w = canvas.clientWidth || 300;
  const h = canvas.clientHeight || 200;
  ctx.clearRect(0, 0, w, h);
  const origin = track[0];
  if (!origin) return;
  const { scale, cx, cy } = fitTrack(track, w, h);
  const px = (p: TrackPoint): [number, number] => {
    const [x, y] = localM(origin, p);
    return [w / 2 + (x - cx) * scale, h / 2 - (y - cy) * scale];
  };
  ctx.strokeStyle = "#4fc3f7";
  ctx.lineWidth = 2;
  ctx.beginPath();
  track.forEach((p, i) => {
    const [x, y] = px(p);
    if (i === 0) ctx.moveTo(x, y);
    else ctx.lineTo(x, y);
  });
  ctx.stroke();
  const [hx, hy] = px(origin);
  ctx.fillStyle = "#66bb6a";
  ctx.fillRect(hx - 4, hy - 4, 8, 8);
  const last = track[track.length - 1];
  if (last) {
    const [x, y] = px(last);
    ctx.fillStyle = "#ffcc00";
    ctx.beginPath();
    ctx.arc(x, y, 5, 0, 2 * Math.PI);
    ctx.fill();
  }
}
