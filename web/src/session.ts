// One render session as the page holds it: opened with OpenSession, its
// stream (stream.ts) feeding the decoder (decoder.ts), the state the server
// last reported, and what happens when the stream ends: attach again to the
// same session (a dropped connection; the server keeps a session 30 s
// without a stream), open it again from its last description when the
// server no longer has it, or stop when the sign-in is gone.
import { ApiError, closeSession, openSession, whoami } from "./api.js";
import { FrameDecoder, type PaintedFrame } from "./decoder.js";
import type {
  EventError,
  OpenSessionResponse,
  PickResult,
  ServerMessage,
  SessionState,
  StreamStats,
} from "./gen/crackvis/v1/render_pb.js";
import type { Severity } from "./messages.js";
import { parsePipeline, serializePipeline, setViewSize } from "./pipeline_xml.js";
import { SessionStream, type EventBody, type StreamEnd } from "./stream.js";

export interface SessionHooks {
  state(state: SessionState): void;
  // latencies: ms from sending each event this frame is the first to reflect
  painted(frame: PaintedFrame, latencies: number[]): void;
  pick(result: PickResult): void;
  eventError(error: EventError): void;
  stats(stats: StreamStats): void;
  report(message: string, severity: Severity): void;
  // The server had lost the session; this is the new one on the same view.
  reopened(session: OpenSessionResponse): void;
  signedOut(message: string): void;
  // The view's size now, for a session opened again.
  viewSize(): { width: number; height: number };
}

function describeEnd(end: StreamEnd): string {
  if (end.code === 1009) return "the server refused a message over its size limit (close 1009)";
  if (end.code === 1006) return "the connection dropped (close 1006)";
  if (end.status) return `${end.status}: ${end.reason || "no reason given"}`;
  return `close ${end.code}${end.reason ? `: ${end.reason}` : ""}`;
}

export class RenderSession {
  private lastState: SessionState | null = null;
  private pipelineXml: string;
  private readonly stream: SessionStream;
  private readonly decoder: FrameDecoder;
  // When each event not yet reflected by a painted frame was sent.
  private readonly sentAt = new Map<bigint, number>();
  private announceReconnect = false;
  private streamsAttached = 0;

  private constructor(
    private opened: OpenSessionResponse,
    xml: string,
    canvas: HTMLCanvasElement,
    private readonly hooks: SessionHooks,
  ) {
    this.pipelineXml = xml;
    this.decoder = new FrameDecoder(canvas, {
      painted: (frame) => this.painted(frame),
      needKeyframe: (why) => {
        hooks.report(`decoder: ${why}; asking for a keyframe`, "warning");
        this.send({ case: "requestKeyframe", value: true });
      },
      failed: (why) => hooks.report(why, "error"),
    });
    this.stream = new SessionStream(opened.sessionId, {
      opened: (reattached) => this.streamOpened(reattached),
      message: (message) => this.received(message),
      ended: (end) => this.ended(end),
    });
  }

  static async open(
    xml: string,
    canvas: HTMLCanvasElement,
    hooks: SessionHooks,
  ): Promise<RenderSession> {
    const opened = await openSession(xml);
    const session = new RenderSession(opened, xml, canvas, hooks);
    session.stream.start();
    return session;
  }

  get id(): string {
    return this.opened.sessionId;
  }
  get info(): OpenSessionResponse {
    return this.opened;
  }
  get state(): SessionState | null {
    return this.lastState;
  }
  get attaches(): number {
    return this.streamsAttached;
  }
  // The description in force as the server last reported it.
  get description(): string {
    return this.pipelineXml;
  }

  send(body: EventBody): bigint {
    const id = this.stream.send(body);
    this.sentAt.set(id, performance.now());
    return id;
  }

  // After signing in again: the stream attaches once more (or the session
  // is opened again if the server dropped it meanwhile).
  resume(): void {
    this.stream.start();
  }

  async close(): Promise<void> {
    this.stream.stop();
    this.decoder.close();
    try {
      await closeSession(this.id);
    } catch {
      // gone already, or the server is away: it closes the session itself
    }
  }

  // The page is going away: the request is kept alive past the page.
  closeOnUnload(): void {
    this.stream.stop();
    closeSession(this.id, true).catch(() => {});
  }

  dropConnection(): void {
    this.stream.drop();
  }

  sendRaw(bytes: Uint8Array): boolean {
    return this.stream.sendRaw(bytes);
  }

  private streamOpened(reattached: boolean): void {
    this.streamsAttached++;
    // A new stream starts with a keyframe, and reflects none of the events
    // the last one lost.
    this.decoder.restart();
    this.sentAt.clear();
    this.announceReconnect = reattached;
  }

  private received(message: ServerMessage): void {
    if (this.announceReconnect) {
      this.announceReconnect = false;
      this.hooks.report("reconnected", "info");
    }
    const m = message.message;
    switch (m.case) {
      case "frame":
        this.decoder.decode(m.value);
        break;
      case "state":
        this.lastState = m.value;
        this.pipelineXml = m.value.pipelineXml || this.pipelineXml;
        this.hooks.state(m.value);
        break;
      case "stats":
        this.hooks.stats(m.value);
        break;
      case "error":
        this.hooks.eventError(m.value);
        break;
      case "pick":
        this.hooks.pick(m.value);
        break;
    }
  }

  private painted(frame: PaintedFrame): void {
    const now = performance.now();
    const latencies: number[] = [];
    for (const [id, sent] of this.sentAt) {
      if (id > frame.lastEventId) continue;
      latencies.push(now - sent);
      this.sentAt.delete(id);
    }
    this.hooks.painted(frame, latencies);
  }

  private async ended(end: StreamEnd): Promise<string | null> {
    const why = describeEnd(end);
    switch (end.status) {
      case "NOT_FOUND":
        return this.reopen(why);
      case "UNAUTHENTICATED":
        this.hooks.signedOut(why);
        return null;
      case "PERMISSION_DENIED":
      case "INVALID_ARGUMENT":
        this.hooks.report(`the stream ended: ${why}`, "error");
        return null;
    }
    // A refused upgrade looks like a dropped connection: only the sign-in
    // check tells a lost cookie from a network problem.
    if (end.code === 1006 && (await this.signedIn()) === false) {
      this.hooks.signedOut("signed out: sign in again to go on with the view");
      return null;
    }
    this.hooks.report(`connection lost (${why}); reconnecting`, "warning");
    return this.id;
  }

  // False when the server says the sign-in is gone, null when it cannot be asked.
  private async signedIn(): Promise<boolean | null> {
    try {
      return (await whoami()) !== null;
    } catch {
      return null;
    }
  }

  // The server no longer has the session (it restarted, or the stream was
  // away past its grace period): the same view in a new session.
  private async reopen(why: string): Promise<string | null> {
    this.hooks.report(`the session is gone (${why}); opening the view again`, "warning");
    try {
      const doc = parsePipeline(this.pipelineXml);
      const { width, height } = this.hooks.viewSize();
      setViewSize(doc, width, height);
      this.opened = await openSession(serializePipeline(doc));
      this.hooks.reopened(this.opened);
      return this.opened.sessionId;
    } catch (e) {
      const error = e instanceof ApiError ? e : new ApiError("UNKNOWN", String(e));
      if (error.code === "UNAUTHENTICATED") {
        this.hooks.signedOut(error.message);
        return null;
      }
      if (error.code === "UNAVAILABLE") return this.id; // try again after the backoff
      this.hooks.report(`cannot open the view again: ${error.message}`, "error");
      return null;
    }
  }
}
