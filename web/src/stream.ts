// The session stream: RenderService.Stream over a WebSocket, one binary
// protobuf per message (ClientEvent up, ServerMessage down), and the
// reconnection that keeps it going. The first message of every connection
// attaches to the session; events sent while no connection is open wait and
// follow the attach. What to do when a connection ends (attach again, attach
// to a re-opened session, give up) is the owner's decision (StreamHooks.ended).
import { create, fromBinary, toBinary, type MessageInitShape } from "@bufbuild/protobuf";
import {
  ClientEventSchema,
  ServerMessageSchema,
  type ClientEvent,
  type ServerMessage,
} from "./gen/crackvis/v1/render_pb.js";
import { statusName } from "./api.js";

// An event's oneof as plain data: { case: "setStep", value: { step: 3 } }.
export type EventBody = NonNullable<MessageInitShape<typeof ClientEventSchema>["event"]>;

export interface StreamEnd {
  code: number; // WebSocket close code: 1000, 1006, 1009, 4000 + gRPC code
  reason: string;
  status: string; // the gRPC status name for 4000..4016, else ""
}

export interface StreamHooks {
  // A connection is open and attached (reattached: not the first one).
  opened(reattached: boolean): void;
  message(message: ServerMessage): void;
  // The connection ended without stop(): the session id to attach to next,
  // or null to give up.
  ended(end: StreamEnd): Promise<string | null>;
}

const kPath = "/rpc/crackvis.v1.RenderService/Stream";
// The Qt client's backoff: 100 ms doubling up to 3 s, back to 100 ms once a
// connection has carried a message.
const kFirstBackoffMs = 100;
const kLastBackoffMs = 3000;
// Events kept while disconnected; beyond it the oldest go (a long outage
// must not replay minutes of camera moves).
const kMaxWaiting = 256;

function streamUrl(): string {
  const scheme = location.protocol === "http:" ? "ws:" : "wss:";
  return `${scheme}//${location.host}${kPath}`;
}

export function endOf(event: CloseEvent): StreamEnd {
  const grpc = event.code >= 4000 && event.code <= 4016;
  const status = grpc ? statusName(event.code - 4000) : "";
  return { code: event.code, reason: event.reason, status };
}

export class SessionStream {
  private socket: WebSocket | null = null;
  private waiting: ClientEvent[] = [];
  private nextEventId = 1n;
  private backoffMs = kFirstBackoffMs;
  private connections = 0;
  private stopped = false;
  private timer = 0;

  constructor(
    private sessionId: string,
    private readonly hooks: StreamHooks,
  ) {}

  get attachedTo(): string {
    return this.sessionId;
  }

  // Connects unless a connection is open or on its way (a resume after
  // signing in again may find the old one still up).
  start(): void {
    this.stopped = false;
    clearTimeout(this.timer);
    if (this.socket === null) this.connect();
  }

  // Ends the stream for good (the session is closed or replaced).
  stop(): void {
    this.stopped = true;
    clearTimeout(this.timer);
    const socket = this.socket;
    this.socket = null;
    socket?.close(1000, "closed by the page");
  }

  // Queues an event; returns its id. Ids increase over the page's life, so
  // they also increase per stream as the protocol asks.
  send(body: EventBody): bigint {
    const eventId = this.nextEventId++;
    const event = create(ClientEventSchema, { eventId, event: body });
    if (this.socket?.readyState === WebSocket.OPEN) {
      this.socket.send(toBinary(ClientEventSchema, event));
    } else {
      this.waiting.push(event);
      if (this.waiting.length > kMaxWaiting) this.waiting.shift();
    }
    return eventId;
  }

  // For the browser test: bytes as they are, past any client-side check.
  sendRaw(bytes: Uint8Array): boolean {
    if (this.socket?.readyState !== WebSocket.OPEN) return false;
    this.socket.send(bytes);
    return true;
  }

  // For the browser test: the connection ends as if the network dropped it
  // (a page cannot reset TCP; the close code 3000 is one no server sends).
  drop(): void {
    this.socket?.close(3000, "dropped by the test hook");
  }

  private connect(): void {
    const socket = new WebSocket(streamUrl());
    socket.binaryType = "arraybuffer";
    this.socket = socket;
    const reattached = this.connections++ > 0;
    let carried = false;
    socket.onopen = () => {
      const attach = create(ClientEventSchema, {
        event: { case: "attachSessionId", value: this.sessionId },
      });
      socket.send(toBinary(ClientEventSchema, attach));
      this.hooks.opened(reattached);
      for (const event of this.waiting.splice(0)) socket.send(toBinary(ClientEventSchema, event));
    };
    socket.onmessage = (event: MessageEvent) => {
      if (!(event.data instanceof ArrayBuffer)) return;
      carried = true;
      this.backoffMs = kFirstBackoffMs;
      this.hooks.message(fromBinary(ServerMessageSchema, new Uint8Array(event.data)));
    };
    socket.onclose = (event: CloseEvent) => {
      if (this.socket !== socket) return; // stopped, or superseded by a newer connection
      this.socket = null;
      if (!carried) this.backoffMs = Math.min(this.backoffMs * 2, kLastBackoffMs);
      void this.afterEnd(endOf(event));
    };
  }

  private async afterEnd(end: StreamEnd): Promise<void> {
    if (this.stopped) return;
    const next = await this.hooks.ended(end);
    // start() may have connected meanwhile (signed in again).
    if (this.stopped || next === null || this.socket !== null) return;
    this.sessionId = next;
    this.timer = window.setTimeout(() => {
      if (!this.stopped) this.connect();
    }, this.backoffMs);
  }
}
