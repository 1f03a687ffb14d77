// One run of the browser page's latency benchmark (tools/bench/browser-vs-client.sh runs it
// alternately with `crackvis bench render`): headless Chromium signs in, chooses FILE (timing
// the first painted frame), sizes the page so that the view is exactly WIDTHxHEIGHT, drags the
// camera with rotate moves at RATE Hz for SECONDS, then makes STILLS isolated still camera moves
// (CameraEvent.still, answered by a full-resolution frame). Latencies are the page's own:
// performance.now() when the event is sent, and when the first frame reflecting it is painted
// on the canvas (after WebCodecs decoded it). Prints one JSON object.
//
// Environment: CRACKVIS_WEB_URL, CRACKVIS_USER, CRACKVIS_PASSWORD, CRACKVIS_FILE,
// CRACKVIS_NODE_MODULES (where playwright-core is: the build tree's web/node_modules),
// CRACKVIS_CHROMIUM (default /usr/bin/chromium); BENCH_SIZE (1280x720), BENCH_SECONDS (5),
// BENCH_RATE (60), BENCH_STILLS (10).
import { createRequire } from "node:module";
import path from "node:path";

const env = (name, fallback) => {
  const value = process.env[name] ?? fallback;
  if (value === undefined) throw new Error(`${name} is not set`);
  return value;
};
const require = createRequire(path.join(env("CRACKVIS_NODE_MODULES"), "noop.js"));
const { chromium } = require("playwright-core");

const [width, height] = env("BENCH_SIZE", "1280x720").split("x").map(Number);
const seconds = Number(env("BENCH_SECONDS", "5"));
const rate = Number(env("BENCH_RATE", "60"));
const stills = Number(env("BENCH_STILLS", "10"));

function percentile(values, p) {
  if (values.length === 0) return null;
  const sorted = [...values].sort((a, b) => a - b);
  return sorted[Math.min(sorted.length - 1, Math.floor((p / 100) * sorted.length))];
}
const summary = (values) => ({
  n: values.length,
  p50: percentile(values, 50),
  p95: percentile(values, 95),
});
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// CPU time of Chromium's processes in ms, by type (browser, renderer, GPU,
// utility) and in all.
async function browserCpuMs(cdp) {
  const { processInfo } = await cdp.send("SystemInfo.getProcessInfo");
  const byType = { all: 0 };
  for (const p of processInfo) {
    byType[p.type] = (byType[p.type] ?? 0) + p.cpuTime * 1000;
    byType.all += p.cpuTime * 1000;
  }
  return byType;
}
const perFrame = (after, before, frames) =>
  Object.fromEntries(
    Object.keys(after).map((type) => [type, frames > 0 ? (after[type] - (before[type] ?? 0)) / frames : null]),
  );

const browser = await chromium.launch({
  executablePath: env("CRACKVIS_CHROMIUM", "/usr/bin/chromium"),
  // BENCH_CHROMIUM_ARGS: extra flags, space-separated (to compare settings).
  args: ["--no-sandbox", ...(process.env.BENCH_CHROMIUM_ARGS ?? "").split(" ").filter(Boolean)],
});
try {
  const context = await browser.newContext({
    ignoreHTTPSErrors: true,
    viewport: { width: 1280, height: 720 },
  });
  const page = await context.newPage();
  // Frames the server sent (ServerMessage.frame: field 1), counted as they
  // arrive, beside the frames the page painted.
  let framesReceived = 0;
  const reductions = {};
  page.on("websocket", (socket) =>
    socket.on("framereceived", ({ payload }) => {
      if (typeof payload === "string" || payload[0] !== 0x0a) return;
      framesReceived++;
      // Frame's leading varint fields (1..8); field 7 is the reduction.
      let i = 1;
      while (payload[i] & 0x80) i++;
      i++;
      while (i < payload.length && (payload[i] & 7) === 0 && payload[i] >> 3 <= 8) {
        const tag = payload[i++] >> 3;
        let value = 0;
        for (let shift = 0; ; shift += 7) {
          const b = payload[i++];
          value += (b & 0x7f) * 2 ** shift;
          if (!(b & 0x80)) break;
        }
        if (tag === 7) reductions[value] = (reductions[value] ?? 0) + 1;
      }
    }),
  );
  const cdp = await browser.newBrowserCDPSession();
  const hook = (body, arg) => page.evaluate(body, arg);

  await page.goto(env("CRACKVIS_WEB_URL"));
  await page.fill("#sign-in-user", env("CRACKVIS_USER"));
  await page.fill("#sign-in-password", env("CRACKVIS_PASSWORD"));
  await page.press("#sign-in-password", "Enter");
  const file = env("CRACKVIS_FILE");
  const entry = page.locator(`.file[data-path="${file}"]`);
  await entry.waitFor();
  // The view (the canvas's box) gets exactly width x height: the window
  // grows by what the page's panels take.
  const box = await page.locator("#view").boundingBox();
  await page.setViewportSize({
    width: Math.round(1280 + width - box.width),
    height: Math.round(720 + height - box.height),
  });

  // A first frame within 1 s of choosing a file (the goal): from the
  // double click that opens it to its first frame painted.
  const chosen = Date.now();
  await entry.dblclick();
  await page.waitForFunction(() => window.crackvisTest?.framesPainted > 0, null, {
    timeout: 60000,
  });
  const firstFrameWallMs = Date.now() - chosen;
  // The page's own figure, from its double-click handler to the frame
  // painted: the wall time above also holds Playwright's checks and mouse
  // events before the first click (about 200 ms).
  const firstFrameMs = await hook(() => window.crackvisTest.firstFrameMs);
  await page.waitForFunction(
    ([w, h]) => {
      const f = window.crackvisTest.lastFrame;
      return f && f.width === w && f.height === h && f.fullResolution;
    },
    [width, height],
    { timeout: 30000 },
  );
  await sleep(1000);

  // The drag: rotate moves at `rate` Hz, as `crackvis bench render` sends them.
  const view = await page.locator("#view").boundingBox();
  const cx = view.x + view.width / 2;
  const cy = view.y + view.height / 2;
  await hook(() => {
    window.crackvisTest.latencies.length = 0;
    if (window.crackvisTest.serverMs) window.crackvisTest.serverMs.length = 0;
  });
  const cpuBefore = await browserCpuMs(cdp);
  const receivedBefore = framesReceived;
  const framesBefore = await hook(() => window.crackvisTest.framesPainted);
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  const moves = Math.round(seconds * rate);
  const start = Date.now();
  for (let i = 1; i <= moves; ++i) {
    const angle = (2 * Math.PI * i) / (rate * 2);
    await page.mouse.move(cx + 0.2 * view.width * Math.sin(angle), cy + 0.1 * view.height * Math.sin(2 * angle));
    const wait = start + (i * 1000) / rate - Date.now();
    if (wait > 0) await sleep(wait);
  }
  await page.mouse.up();
  // The server's part over the frames painted while dragging, as the C++
  // client counts it (a page built before it had none).
  const serverMs = await hook(() => [...(window.crackvisTest.serverMs ?? [])]);
  await sleep(500);
  const dragMs = Date.now() - start;
  const dragged = await hook(() => ({
    latencies: [...window.crackvisTest.latencies],
    frames: window.crackvisTest.framesPainted,
    stats: window.crackvisTest.stats,
    decodeMs: [...window.crackvisTest.decodeMs],
  }));
  const cpuAfter = await browserCpuMs(cdp);
  const dragReceived = framesReceived - receivedBefore;
  const dragFrames = dragged.frames - framesBefore;

  // Still moves: one at a time, each waiting for its full-resolution frame.
  await sleep(500);
  await hook(() => {
    window.crackvisTest.latencies.length = 0;
  });
  for (let i = 0; i < stills; ++i) {
    const before = await hook(() => window.crackvisTest.latencies.length);
    await hook(() => window.crackvisTest.stillCamera(1, 0.05, 0));
    await page.waitForFunction((n) => window.crackvisTest.latencies.length > n, before, {
      timeout: 30000,
    });
    await sleep(200);
  }
  const still = await hook(() => [...window.crackvisTest.latencies]);

  const result = {
    size: `${width}x${height}`,
    first_frame_ms: firstFrameMs ?? firstFrameWallMs,
    first_frame_wall_ms: firstFrameWallMs,
    drag_event_to_paint_ms: summary(dragged.latencies),
    still_event_to_paint_ms: summary(still),
    drag_fps: (dragFrames * 1000) / dragMs,
    drag_fps_received: (dragReceived * 1000) / dragMs,
    reductions_received: reductions,
    decode_ms: summary(dragged.decodeMs),
    server_event_to_send_ms: summary(serverMs),
    bitrate_mbps: dragged.stats ? dragged.stats.bitrateBps / 1e6 : null,
    server_frames_dropped: dragged.stats ? dragged.stats.framesDropped : null,
    browser_cpu_ms_per_frame: dragFrames > 0 ? (cpuAfter.all - cpuBefore.all) / dragFrames : null,
    browser_cpu_ms_per_frame_by_process: perFrame(cpuAfter, cpuBefore, dragFrames),
    chromium: browser.version(),
  };
  console.log(JSON.stringify(result));
} finally {
  await browser.close();
}
