// crackvis-render's HTTP side as the page uses it: signing in and out, and
// the unary RenderService calls as binary protobuf over POST /rpc/... (the
// session cookie authenticates them). Every failure becomes an ApiError
// carrying the gRPC status name the server answered with, so the page can
// tell a lost sign-in (UNAUTHENTICATED) from a refused request.
import {
  create,
  fromBinary,
  toBinary,
  type DescMessage,
  type MessageInitShape,
  type MessageShape,
} from "@bufbuild/protobuf";
import {
  DescribeRequestSchema,
  DescribeResponseSchema,
  ListFilesRequestSchema,
  ListFilesResponseSchema,
  type DescribeResponse,
  type FileEntry,
} from "./gen/crackvis/v1/data_pb.js";
import {
  CloseSessionRequestSchema,
  CloseSessionResponseSchema,
  OpenSessionRequestSchema,
  OpenSessionResponseSchema,
  SnapshotRequestSchema,
  SnapshotResponseSchema,
  StepHistoryRequestSchema,
  StepHistoryResponseSchema,
  type OpenSessionResponse,
  type SnapshotResponse,
  type StepHistoryResponse,
} from "./gen/crackvis/v1/render_pb.js";

const kService = "/rpc/crackvis.v1.RenderService/";

// google.rpc.Code by value: WebSocket closes carry 4000 + the code.
const kStatusNames = [
  "OK",
  "CANCELLED",
  "UNKNOWN",
  "INVALID_ARGUMENT",
  "DEADLINE_EXCEEDED",
  "NOT_FOUND",
  "ALREADY_EXISTS",
  "PERMISSION_DENIED",
  "RESOURCE_EXHAUSTED",
  "FAILED_PRECONDITION",
  "ABORTED",
  "OUT_OF_RANGE",
  "UNIMPLEMENTED",
  "INTERNAL",
  "UNAVAILABLE",
  "DATA_LOSS",
  "UNAUTHENTICATED",
];

export function statusName(code: number): string {
  return kStatusNames[code] ?? `status ${code}`;
}

export class ApiError extends Error {
  constructor(
    readonly code: string,
    message: string,
    readonly httpStatus = 0,
  ) {
    super(message);
  }
}

// Called when any call finds the sign-in gone (the cookie expired, the
// server restarted): the page shows its sign-in form.
let unauthenticated: (message: string) => void = () => {};

export function onUnauthenticated(handler: (message: string) => void): void {
  unauthenticated = handler;
}

// The server answers errors as {"code": "NOT_FOUND", "message": "..."};
// anything else (a proxy's HTML page) is reported by its HTTP status.
async function errorOf(response: Response): Promise<ApiError> {
  let code = response.status === 401 ? "UNAUTHENTICATED" : "UNKNOWN";
  let message = `HTTP ${response.status} ${response.statusText}`.trim();
  try {
    const body = (await response.json()) as { code?: unknown; message?: unknown };
    if (typeof body.code === "string") code = body.code;
    if (typeof body.message === "string") message = body.message;
  } catch {
    // not JSON: keep the HTTP status
  }
  return new ApiError(code, message, response.status);
}

async function send(path: string, init: RequestInit): Promise<Response> {
  let response: Response;
  try {
    response = await fetch(path, { credentials: "same-origin", cache: "no-store", ...init });
  } catch (e) {
    throw new ApiError("UNAVAILABLE", `cannot reach the server (${String(e)})`);
  }
  if (response.ok) return response;
  const error = await errorOf(response);
  if (error.code === "UNAUTHENTICATED" && path.startsWith(kService)) {
    unauthenticated(error.message);
  }
  throw error;
}

async function userOf(response: Response): Promise<string> {
  const body = (await response.json()) as { user?: unknown };
  return typeof body.user === "string" ? body.user : "";
}

export type Credentials = { user: string; password: string } | { token: string };

// Basic or Bearer in a header, never in the URL: the secret stays out of
// access logs and the browser's history.
export async function login(credentials: Credentials): Promise<string> {
  const authorization =
    "token" in credentials
      ? `Bearer ${credentials.token}`
      : `Basic ${base64Utf8(`${credentials.user}:${credentials.password}`)}`;
  const response = await send("/api/login", {
    method: "POST",
    headers: { Authorization: authorization },
  });
  return userOf(response);
}

export async function logout(): Promise<void> {
  await send("/api/logout", { method: "POST" });
}

// The signed-in user, or null when the cookie is missing or expired.
export async function whoami(): Promise<string | null> {
  try {
    return await userOf(await send("/api/whoami", { method: "GET" }));
  } catch (e) {
    if (e instanceof ApiError && e.code === "UNAUTHENTICATED") return null;
    throw e;
  }
}

function base64Utf8(text: string): string {
  let binary = "";
  for (const byte of new TextEncoder().encode(text)) binary += String.fromCharCode(byte);
  return btoa(binary);
}

async function call<I extends DescMessage, O extends DescMessage>(
  method: string,
  input: I,
  request: MessageInitShape<I>,
  output: O,
  keepalive = false,
): Promise<MessageShape<O>> {
  const response = await send(kService + method, {
    method: "POST",
    headers: { "Content-Type": "application/x-protobuf" },
    body: toBinary(input, create(input, request)),
    keepalive,
  });
  return fromBinary(output, new Uint8Array(await response.arrayBuffer()));
}

export async function listFiles(folder = ""): Promise<FileEntry[]> {
  const response = await call(
    "ListFiles",
    ListFilesRequestSchema,
    { folder, recursive: true },
    ListFilesResponseSchema,
  );
  return response.files;
}

export function describe(file: string): Promise<DescribeResponse> {
  return call("Describe", DescribeRequestSchema, { file }, DescribeResponseSchema);
}

// With a crack method, the scalars gain the crack's numbers per step (the
// server runs the method over every step: seconds for a large file).
export function stepHistory(file: string, cracks = ""): Promise<StepHistoryResponse> {
  return call("StepHistory", StepHistoryRequestSchema, { file, cracks }, StepHistoryResponseSchema);
}

export function openSession(pipelineXml: string): Promise<OpenSessionResponse> {
  return call("OpenSession", OpenSessionRequestSchema, { pipelineXml }, OpenSessionResponseSchema);
}

// Width and height 0: the session's view size.
export function snapshot(sessionId: string, width = 0, height = 0): Promise<SnapshotResponse> {
  return call(
    "Snapshot",
    SnapshotRequestSchema,
    { sessionId, width, height },
    SnapshotResponseSchema,
  );
}

// keepalive: the request outlives a page being closed.
export async function closeSession(sessionId: string, keepalive = false): Promise<void> {
  await call(
    "CloseSession",
    CloseSessionRequestSchema,
    { sessionId },
    CloseSessionResponseSchema,
    keepalive,
  );
}
