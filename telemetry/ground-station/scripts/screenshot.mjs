// Screenshot of the main view for the README: the app against a running
// `taulink-sim --serve ADDR` (= `flight-sitl serve`), 27 s into its world (armed, hovering in
// rate mode after the attitude steps). Usage: node scripts/screenshot.mjs http://127.0.0.1:8018/ OUT.png
import { chromium } from "@playwright/test";

const [url = "http://127.0.0.1:8018/", out = "screenshot.png"] = process.argv.slice(2);
const browser = await chromium.launch({ executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium", args: ["--no-sandbox"] });
const page = await browser.newPage({ viewport: { width: 1280, height: 1000 } });
await page.goto(`${url}?sim`);
await page.waitForTimeout(27_000);
await page.screenshot({ path: out, fullPage: true });
await browser.close();
