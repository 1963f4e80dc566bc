/**
 * Browser tests: Debian's Chromium (no browser download) against `taulink-sim --serve`,
 * built beforehand (`cargo build --release -p taulink-sim`) and serving dist/.
 */
import { defineConfig } from "@playwright/test";

const port = Number(process.env.TAULINK_GCS_PORT ?? 8019);

export default defineConfig({
  testDir: "e2e",
  timeout: 60_000,
  workers: 1,
  reporter: [["list"]],
  use: {
    baseURL: `http://127.0.0.1:${port}/`,
    launchOptions: { executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium", args: ["--no-sandbox"] },
    acceptDownloads: true,
  },
  webServer: {
    command: `../../target/release/taulink-sim --serve 127.0.0.1:${port} --dist dist`,
    url: `http://127.0.0.1:${port}/`,
    reuseExistingServer: false,
    timeout: 30_000,
  },
});
