// Turns the stream's H.264 access units (Annex B, SPS and PPS in every
// keyframe) into pictures on a 2D canvas with WebCodecs. The decoder is
// configured from the first keyframe's SPS and again whenever a keyframe
// carries a different SPS (a resize restarts the server's encoder); after a
// decoder error it drops frames until a keyframe, which it asks for.
//
// A picture of the canvas's size is converted to RGBA by VideoFrame.copyTo
// and put on the canvas: drawImage of a VideoFrame took 15-20 ms of the
// page's main thread per 1280x720 frame in headless Chromium 156 (software
// compositing), copyTo and putImageData about 1 ms (docs/benchmarks.md,
// "The browser page"). Other sizes (a resize in flight), and browsers whose
// copyTo cannot convert, are drawn scaled with drawImage.
import type { Frame } from "./gen/crackvis/v1/render_pb.js";

export const kNoWebCodecs =
  "This browser cannot show the stream: it lacks WebCodecs H.264 decoding (VideoDecoder), " +
  "which Chrome and Edge 94 or later, Firefox 130 or later and Safari 16.4 or later offer " +
  "on pages served over HTTPS.";

export function hasWebCodecs(): boolean {
  return typeof window.VideoDecoder === "function";
}

export interface PaintedFrame {
  frameId: bigint;
  lastEventId: bigint;
  step: number;
  width: number;
  height: number;
  keyframe: boolean;
  fullResolution: boolean;
  decodeMs: number; // from handing the access unit to the decoder to its picture painted
  // The server's part: from receiving the last event this frame reflects
  // to sending it (FrameTimings.event_to_send_ms; 0: no new event).
  serverMs: number;
  // "copy": converted by VideoFrame.copyTo and put; "scaled": drawImage.
  paintedBy: "copy" | "scaled";
}

export interface DecoderHooks {
  painted(frame: PaintedFrame): void;
  // The decoder lost its state (why): the next frame must be a keyframe.
  needKeyframe(why: string): void;
  // Decoding cannot work in this browser (an unsupported profile).
  failed(why: string): void;
}

const kNalSps = 7;
// Errors in a row without a picture before decoding is given up: a profile
// the browser cannot decode fails every keyframe alike.
const kMaxFailures = 3;

// The first SPS NAL unit of an Annex B access unit, from its header byte
// to the next start code.
export function findSps(unit: Uint8Array): Uint8Array | null {
  for (let i = 0; i + 3 < unit.length; i++) {
    if (unit[i] !== 0 || unit[i + 1] !== 0 || unit[i + 2] !== 1) continue;
    const start = i + 3;
    if ((unit[start] & 0x1f) !== kNalSps) continue;
    // A NAL unit's bytes never hold 00 00 00 or 00 00 01 (emulation
    // prevention): the first such triple starts the next unit.
    const startCodeAt = (k: number) => unit[k] === 0 && unit[k + 1] === 0 && unit[k + 2] <= 1;
    let end = start + 1;
    while (end + 2 < unit.length && !startCodeAt(end)) end++;
    return unit.subarray(start, end + 2 < unit.length ? end : unit.length);
  }
  return null;
}

// "avc1.PPCCLL": profile_idc, the constraint flags and level_idc, the three
// bytes after the SPS's NAL header (never escaped: profile_idc is not 0).
export function codecOf(sps: Uint8Array): string {
  const hex = (b: number) => b.toString(16).padStart(2, "0").toUpperCase();
  return `avc1.${hex(sps[1])}${hex(sps[2])}${hex(sps[3])}`;
}

function sameBytes(a: Uint8Array | null, b: Uint8Array): boolean {
  return a !== null && a.length === b.length && a.every((byte, i) => byte === b[i]);
}

interface Pending {
  frame: Frame;
  handedAt: number;
}

export class FrameDecoder {
  private decoder: VideoDecoder | null = null;
  private sps: Uint8Array | null = null;
  private waitingForKey = true;
  private failures = 0;
  private gaveUp = false;
  private timestamp = 0;
  private readonly pending = new Map<number, Pending>();
  private readonly context: CanvasRenderingContext2D;
  // Pictures are painted in decode order, each after the one before.
  private painting: Promise<void> = Promise.resolve();
  private rgba: ImageData | null = null;
  private copyConverts = true; // until a copyTo with a format fails
  private generation = 0; // counts close(): a closed decoder's pictures are not painted

  constructor(
    private readonly canvas: HTMLCanvasElement,
    private readonly hooks: DecoderHooks,
  ) {
    const context = canvas.getContext("2d", { alpha: false });
    if (!context) throw new Error("no 2D canvas context");
    this.context = context;
    // The page says so once (kNoWebCodecs); frames are dropped quietly.
    this.gaveUp = !hasWebCodecs();
  }

  // A new stream (a reconnect) starts with a keyframe: nothing before it
  // can be decoded.
  restart(): void {
    this.waitingForKey = true;
  }

  decode(frame: Frame): void {
    if (this.gaveUp) return;
    let sps: Uint8Array | null = null;
    if (frame.keyframe) {
      sps = findSps(frame.h264);
      if (sps === null) {
        this.hooks.needKeyframe("a keyframe without an SPS");
        return;
      }
    } else if (this.waitingForKey || this.decoder === null) {
      return; // it refers to pictures this decoder never saw
    }
    const timestamp = ++this.timestamp;
    this.pending.set(timestamp, { frame, handedAt: performance.now() });
    try {
      if (sps !== null && (this.decoder === null || !sameBytes(this.sps, sps))) this.configure(sps);
      const type = frame.keyframe ? "key" : "delta";
      this.decoder!.decode(new EncodedVideoChunk({ type, timestamp, data: frame.h264 }));
      this.waitingForKey = false;
    } catch (e) {
      // configure() refused the codec string, or the decoder closed meanwhile
      this.close();
      this.lost(e instanceof DOMException ? e : new DOMException(String(e), "EncodingError"));
    }
  }

  close(): void {
    if (this.decoder && this.decoder.state !== "closed") this.decoder.close();
    this.decoder = null;
    this.pending.clear();
    this.generation++;
  }

  private configure(sps: Uint8Array): void {
    this.sps = sps.slice();
    if (this.decoder === null || this.decoder.state === "closed") {
      this.decoder = new VideoDecoder({
        output: (picture) => this.paint(picture),
        error: (e) => this.lost(e),
      });
    }
    // No description: the access units stay in Annex B with in-band SPS/PPS.
    this.decoder.configure({ codec: codecOf(sps), optimizeForLatency: true });
  }

  private paint(picture: VideoFrame): void {
    const entry = this.pending.get(picture.timestamp);
    this.pending.delete(picture.timestamp);
    this.failures = 0;
    const generation = this.generation;
    this.painting = this.painting
      .then(() => this.show(picture, entry, generation))
      // A picture that cannot be painted is skipped; the next one paints.
      .catch(() => undefined);
  }

  private async show(
    picture: VideoFrame,
    entry: Pending | undefined,
    generation: number,
  ): Promise<void> {
    let paintedBy: PaintedFrame["paintedBy"];
    try {
      // Pictures of a closed decoder stay off the canvas (a new session's).
      if (generation !== this.generation) return;
      paintedBy = await this.draw(picture);
    } finally {
      picture.close();
    }
    if (!entry) return;
    const f = entry.frame;
    this.hooks.painted({
      frameId: f.frameId,
      lastEventId: f.lastEventId,
      step: f.step,
      width: f.width,
      height: f.height,
      keyframe: f.keyframe,
      fullResolution: f.fullResolution,
      decodeMs: performance.now() - entry.handedAt,
      serverMs: f.timings?.eventToSendMs ?? 0,
      paintedBy,
    });
  }

  private async draw(picture: VideoFrame): Promise<PaintedFrame["paintedBy"]> {
    const fits = () =>
      picture.displayWidth === this.canvas.width && picture.displayHeight === this.canvas.height;
    if (this.copyConverts && fits()) {
      const { width, height } = this.canvas;
      // TypeScript's DOM types lack copyTo's format option (Chrome 127+).
      // Browsers before it ignore the option and would copy the decoder's
      // own format (I420): its size tells.
      const rgba = { format: "RGBA" } as VideoFrameCopyToOptions;
      if (picture.allocationSize(rgba) !== width * height * 4) {
        this.copyConverts = false;
      } else {
        if (this.rgba === null || this.rgba.width !== width || this.rgba.height !== height) {
          this.rgba = new ImageData(width, height);
        }
        try {
          await picture.copyTo(this.rgba.data, rgba);
        } catch {
          this.copyConverts = false;
        }
        // The canvas may have been resized meanwhile (a new view size).
        if (this.copyConverts && fits()) {
          this.context.putImageData(this.rgba, 0, 0);
          return "copy";
        }
      }
    }
    this.context.drawImage(picture, 0, 0, this.canvas.width, this.canvas.height);
    return "scaled";
  }

  // The decoder closes itself after an error; the next keyframe makes a new one.
  private lost(error: DOMException): void {
    this.decoder = null;
    this.sps = null;
    this.waitingForKey = true;
    this.pending.clear();
    const why = `${error.name}: ${error.message}`;
    if (++this.failures >= kMaxFailures) {
      this.gaveUp = true;
      this.hooks.failed(`this browser cannot decode the stream (${why})`);
      return;
    }
    this.hooks.needKeyframe(why);
  }
}
