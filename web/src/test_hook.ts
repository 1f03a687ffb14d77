// window.crackvisTest: what the browser test (tests/web/browser.test.mjs)
// reads of the page, and the few faults it injects. The page only writes
// it; nothing the page does depends on it.

export interface FrameSeen {
  step: number;
  width: number;
  height: number;
  lastEventId: number;
  frameId: number;
  keyframe: boolean;
  fullResolution: boolean;
}

export interface StateSeen {
  step: number;
  stepCount: number;
  width: number;
  height: number;
  playing: boolean;
  pipelineXml: string;
}

export interface CrackvisTest {
  framesPainted: number;
  // From a file chosen to open (the Data pane's double click or Open) to its
  // session's first frame painted, in ms; null until that frame.
  firstFrameMs: number | null;
  lastFrame: FrameSeen | null;
  lastPick: { kind: string; index: number; text: string } | null;
  lastError: string;
  latencies: number[]; // ms, event sent -> first frame reflecting it painted
  decodeMs: number[];
  serverMs: number[]; // of frames reflecting a new event: the server's part of their latency
  // Frames put on the canvas by VideoFrame.copyTo and by drawImage (decoder.ts).
  paintedBy: { copy: number; scaled: number };
  readonly sessionId: string;
  readonly attaches: number; // streams attached in this session (1 + reconnects)
  lastEventId: number; // of the last event the page sent
  state: StateSeen | null;
  // The stream's connection closes as if the network dropped it.
  dropConnection(): void;
  // A ClientEvent of `bytes` bytes or more, straight onto the stream.
  sendOversized(bytes: number): boolean;
  // The view's Snapshot PNG, as the Screenshot button gets it.
  snapshotPng(): Promise<Blob>;
  // A camera move that is not part of a drag (CameraEvent.still: a scripted
  // view), answered by a full-resolution frame: the benchmark's still move.
  stillCamera(kind: number, dx: number, dy: number): void;
  // The last StreamStats (fps, bitrate), as the status line shows them.
  stats: { fps: number; bitrateBps: number; framesDropped: number } | null;
  // The Steps plot's broken bonds per step, as last read.
  brokenBonds: number[];
}

// Kept short: a long run must not grow the page's memory.
const kKept = 1000;

export function keep(list: number[], value: number): void {
  list.push(value);
  if (list.length > kKept) list.shift();
}

// What the page answers when asked (the session it holds now).
type Live = Pick<CrackvisTest, "sessionId" | "attaches">;
type Faults = Pick<
  CrackvisTest,
  "dropConnection" | "sendOversized" | "snapshotPng" | "stillCamera"
>;

export function installTestHook(live: () => Live, faults: Faults): CrackvisTest {
  const hook: CrackvisTest = {
    framesPainted: 0,
    firstFrameMs: null,
    lastFrame: null,
    lastPick: null,
    lastError: "",
    latencies: [],
    decodeMs: [],
    serverMs: [],
    paintedBy: { copy: 0, scaled: 0 },
    lastEventId: 0,
    state: null,
    stats: null,
    brokenBonds: [],
    get sessionId() {
      return live().sessionId;
    },
    get attaches() {
      return live().attaches;
    },
    ...faults,
  };
  (window as unknown as { crackvisTest: CrackvisTest }).crackvisTest = hook;
  return hook;
}
