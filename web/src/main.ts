// crackvis's browser client: the page's wiring. Signing in, the Data pane,
// opening a file into a render session, the view's input and size, the
// time bar and Steps plot, the pipeline panel, screenshots and saved views,
// the messages pane and the status line. The pieces live in their own
// modules; this one connects them and keeps the page's state.
import * as api from "./api.js";
import { hasWebCodecs, kNoWebCodecs, type PaintedFrame } from "./decoder.js";
import { byId, download } from "./dom.js";
import { showFiles, summarize } from "./files.js";
import { create, toBinary } from "@bufbuild/protobuf";
import type { DescribeResponse } from "./gen/crackvis/v1/data_pb.js";
import {
  CameraEvent_Kind,
  ClientEventSchema,
  type EventError,
  type OpenSessionResponse,
  type PickResult,
  type SessionState,
  type StreamStats,
} from "./gen/crackvis/v1/render_pb.js";
import { attachViewInput } from "./input.js";
import { MessageLog, type Severity } from "./messages.js";
import { PipelinePanel } from "./panel.js";
import {
  clonePipeline,
  fileOf,
  layer,
  parsePipeline,
  removeCamera,
  serializePipeline,
  setData,
  setViewSize,
} from "./pipeline_xml.js";
import { StepPlot } from "./plot.js";
import { RenderSession } from "./session.js";
import { installTestHook, keep } from "./test_hook.js";

const ui = {
  user: byId("user", HTMLElement),
  browserNote: byId("browser-note", HTMLElement),
  signOut: byId("sign-out", HTMLButtonElement),
  signIn: byId("sign-in", HTMLElement),
  signInForm: byId("sign-in-form", HTMLFormElement),
  signInUser: byId("sign-in-user", HTMLInputElement),
  signInPassword: byId("sign-in-password", HTMLInputElement),
  signInToken: byId("sign-in-token", HTMLInputElement),
  signInError: byId("sign-in-error", HTMLElement),
  workspace: byId("workspace", HTMLElement),
  files: byId("files", HTMLElement),
  pathForm: byId("path-form", HTMLFormElement),
  path: byId("file-path", HTMLInputElement),
  listPath: byId("list-path", HTMLButtonElement),
  openPath: byId("open-path", HTMLButtonElement),
  description: byId("description", HTMLElement),
  viewport: byId("viewport", HTMLElement),
  view: byId("view", HTMLCanvasElement),
  viewNote: byId("view-note", HTMLElement),
  pick: byId("pick", HTMLElement),
  play: byId("play", HTMLButtonElement),
  step: byId("step", HTMLInputElement),
  stepLabel: byId("step-label", HTMLElement),
  follow: byId("follow", HTMLButtonElement),
  live: byId("live", HTMLElement),
  stepsPerSecond: byId("steps-per-second", HTMLInputElement),
  screenshot: byId("screenshot", HTMLButtonElement),
  saveView: byId("save-view", HTMLButtonElement),
  openView: byId("open-view", HTMLButtonElement),
  viewFile: byId("view-file", HTMLInputElement),
  fit: byId("fit", HTMLButtonElement),
  plot: byId("plot", HTMLCanvasElement),
  plotScalar: byId("plot-scalar", HTMLSelectElement),
  plotAxis: byId("plot-axis", HTMLSelectElement),
  crackNumbers: byId("crack-numbers", HTMLButtonElement),
  panel: byId("panel", HTMLElement),
  messages: byId("messages", HTMLElement),
  latest: byId("latest-message", HTMLElement),
  status: byId("status", HTMLElement),
};

// The server's limits on a view (docs/protocol.md, Resize): even sizes.
const kMinSize = 16;
const kMaxWidth = 3840;
const kMaxHeight = 2160;
const kResizeDebounceMs = 150;
const kStatusEveryMs = 500;
const kRecent = 30;
// How long a Describe answer is reused for the same file (describing()).
const kDescribeKeptMs = 2000;
// The longest a new view's Steps plot waits for its first frame (openView).
const kHistoryAfterMs = 3000;

function evenWithin(value: number, most: number): number {
  return Math.min(most, Math.max(kMinSize, Math.floor(value) & ~1));
}

function messageOf(e: unknown): string {
  if (e instanceof api.ApiError) {
    return e.code === "UNKNOWN" ? e.message : `${e.message} (${e.code})`;
  }
  return e instanceof Error ? e.message : String(e);
}

function median(values: number[]): number {
  if (values.length === 0) return NaN;
  const sorted = [...values].sort((a, b) => a - b);
  return sorted[Math.floor(sorted.length / 2)];
}

// The status line's figures are over the last few frames.
function recent(list: number[], value: number): void {
  list.push(value);
  if (list.length > kRecent) list.shift();
}

function mean(values: number[]): number {
  return values.length === 0 ? NaN : values.reduce((a, b) => a + b, 0) / values.length;
}

function baseName(file: string): string {
  return (file.split("/").pop() ?? file).replace(/\.h5$/i, "");
}

class App {
  private session: RenderSession | null = null;
  private file = "";
  private readonly log = new MessageLog(ui.messages, ui.latest);
  private readonly panel = new PipelinePanel(ui.panel, (doc) => this.panelChanged(doc));
  private readonly plot = new StepPlot(ui.plot, (step) => this.setStep(step));
  // The crack method whose numbers the Steps plot shows ("" none); kept for
  // the file's later reads (a live file), dropped when another file opens.
  private historyCracks = "";
  private readonly test = installTestHook(
    () => ({ sessionId: this.session?.id ?? "", attaches: this.session?.attaches ?? 0 }),
    {
      dropConnection: () => this.session?.dropConnection(),
      sendOversized: (bytes) => this.sendOversized(bytes),
      snapshotPng: () => this.snapshotPng(),
      stillCamera: (kind, dx, dy) =>
        this.send({ case: "camera", value: { kind, dx, dy, still: true } }),
    },
  );
  private stats: StreamStats | null = null;
  private readonly latencies: number[] = [];
  private readonly decodeMs: number[] = [];
  // The last Describe, shared while on its way and for kDescribeKeptMs after
  // its answer (a double click's three Describes: see describing()).
  private lastDescribe: {
    file: string;
    reply: Promise<DescribeResponse>;
    answeredAt: number | null;
  } | null = null;
  private opens = 0; // views asked for: the last one wins (openView)
  private shownPanelKey = "";
  private crackCause = "";
  private sentSize = { width: 0, height: 0 };
  private resizeTimer = 0;
  private sliderHeld = false;
  // A live file: whether it is one, how many steps it had, when the last
  // came, and when the Steps plot was last read again.
  private live = { live: false, following: false, ended: false, steps: 0, lastStepAt: 0, plotAt: 0 };

  start(): void {
    if (!hasWebCodecs()) {
      ui.browserNote.textContent = kNoWebCodecs;
      ui.browserNote.hidden = false;
    }
    api.onUnauthenticated((message) => this.signedOut(message));
    this.wireSignIn();
    this.wireData();
    this.wireView();
    this.wireTimeBar();
    this.wireTools();
    window.addEventListener("pagehide", () => this.session?.closeOnUnload());
    window.setInterval(() => this.showStatus(), kStatusEveryMs);
    void this.checkSignIn();
  }

  report(message: string, severity: Severity = "info"): void {
    this.log.report(message, severity);
    if (severity === "error") this.test.lastError = message;
  }

  // --- signing in

  private async checkSignIn(): Promise<void> {
    try {
      const user = await api.whoami();
      if (user) this.signedIn(user);
      else this.showSignIn("");
    } catch (e) {
      this.showSignIn(`cannot reach the server: ${messageOf(e)}`);
    }
  }

  private wireSignIn(): void {
    ui.signInForm.addEventListener("submit", (event) => {
      event.preventDefault();
      void this.signIn();
    });
    ui.signOut.addEventListener("click", () => void this.signOut());
  }

  private async signIn(): Promise<void> {
    ui.signInError.textContent = "";
    const token = ui.signInToken.value.trim();
    const credentials: api.Credentials = token
      ? { token }
      : { user: ui.signInUser.value.trim(), password: ui.signInPassword.value };
    try {
      this.signedIn(await api.login(credentials));
    } catch (e) {
      ui.signInError.textContent = `Sign-in refused: ${messageOf(e)}`;
    } finally {
      ui.signInPassword.value = "";
      ui.signInToken.value = "";
    }
  }

  private signedIn(user: string): void {
    ui.user.textContent = user;
    ui.signOut.hidden = false;
    ui.signIn.hidden = true;
    ui.workspace.hidden = false;
    void this.listFiles("");
    // A session the sign-in was lost under goes on where it was.
    this.session?.resume();
  }

  private showSignIn(message: string): void {
    ui.signIn.hidden = false;
    ui.workspace.hidden = true;
    ui.signOut.hidden = true;
    ui.user.textContent = "";
    ui.signInError.textContent = message;
    ui.signInUser.focus();
  }

  private signedOut(message: string): void {
    this.showSignIn(message);
    this.report(message, "warning");
  }

  private async signOut(): Promise<void> {
    await this.closeSession();
    try {
      await api.logout();
    } catch (e) {
      this.report(`sign-out: ${messageOf(e)}`, "warning");
    }
    this.showSignIn("");
  }

  // --- the Data pane

  private wireData(): void {
    ui.pathForm.addEventListener("submit", (event) => {
      event.preventDefault();
      void this.describe(ui.path.value.trim());
    });
    ui.listPath.addEventListener("click", () => void this.listFiles(ui.path.value.trim()));
    ui.openPath.addEventListener("click", () => void this.openFile(ui.path.value.trim()));
  }

  private async listFiles(folder: string): Promise<void> {
    try {
      const files = await api.listFiles(folder);
      showFiles(ui.files, files, {
        chosen: (file) => {
          ui.path.value = file;
          void this.describe(file);
        },
        opened: (file) => void this.openFile(file),
      });
      const count = `${files.length} ${files.length === 1 ? "file" : "files"}`;
      this.report(folder ? `${count} in ${folder}` : count);
    } catch (e) {
      this.report(`cannot list ${folder ? `'${folder}'` : "the files"}: ${messageOf(e)}`, "error");
    }
  }

  // The summary, and the file's extra arrays offered in the panel.
  private async describe(file: string): Promise<boolean> {
    if (!file) return false;
    try {
      const summary = summarize(file, await this.describing(file));
      ui.description.textContent = summary.text;
      this.panel.setExtras(summary.particleExtras, summary.bondExtras);
      return true;
    } catch (e) {
      const message = `cannot describe ${file}: ${messageOf(e)}`;
      ui.description.textContent = message;
      this.report(message, "error");
      return false;
    }
  }

  // A Describe of `file`, or the last one while it is on its way or just
  // answered: a double click describes on each click and again to open, and
  // the session waited for the last (three Describes of one file, 60-90 ms
  // on cuboid A). A refusal is shared only with those already waiting.
  private describing(file: string): Promise<DescribeResponse> {
    const last = this.lastDescribe;
    const fresh =
      last !== null &&
      last.file === file &&
      (last.answeredAt === null || performance.now() - last.answeredAt < kDescribeKeptMs);
    if (fresh) return last.reply;
    const reply = api.describe(file);
    const entry = { file, reply, answeredAt: null as number | null };
    this.lastDescribe = entry;
    reply.then(
      () => {
        entry.answeredAt = performance.now();
      },
      () => {
        if (this.lastDescribe === entry) this.lastDescribe = null;
      },
    );
    return reply;
  }

  // --- sessions

  // The viewport's size, or the last one sent while it is not laid out
  // (the workspace hidden behind the sign-in form has no size).
  private viewSize(): { width: number; height: number } {
    const { clientWidth, clientHeight } = ui.viewport;
    if ((clientWidth === 0 || clientHeight === 0) && this.sentSize.width > 0) return this.sentSize;
    return {
      width: evenWithin(clientWidth, kMaxWidth),
      height: evenWithin(clientHeight, kMaxHeight),
    };
  }

  // A file from the Data pane: the panel's settings, the last step, the
  // camera fitted to this file (the Qt client's File > Open).
  private async openFile(file: string): Promise<void> {
    if (!file) return;
    const chosenAt = performance.now();
    this.test.firstFrameMs = null;
    const doc = this.panel.description();
    setData(doc, file, -1);
    removeCamera(doc);
    await this.openView(doc, chosenAt);
  }

  // `chosenAt`: when the user chose the file, to time the new session's
  // first frame painted (crackvisTest.firstFrameMs).
  private async openView(doc: XMLDocument, chosenAt: number | null = null): Promise<void> {
    const file = fileOf(doc);
    // The last view asked for wins: an open overtaken by a newer one while
    // it waits closes its session (it would paint on the same canvas).
    const open = ++this.opens;
    // A file Describe refuses (a foreign folder, a typo) would be refused
    // again by OpenSession: one message is enough.
    if (!(await this.describe(file)) || open !== this.opens) return;
    const size = this.viewSize();
    setViewSize(doc, size.width, size.height);
    await this.closeSession();
    // The Steps plot's StepHistory waits for the first frame (or
    // kHistoryAfterMs): the server computes it while it would draw that frame.
    const firstFrame = { chosenAt, history: () => {} };
    let session: RenderSession;
    try {
      session = await RenderSession.open(serializePipeline(doc), ui.view, {
        state: (state) => this.stateChanged(state),
        painted: (frame, latencies) => {
          if (firstFrame.chosenAt !== null) {
            this.test.firstFrameMs = performance.now() - firstFrame.chosenAt;
            firstFrame.chosenAt = null;
          }
          firstFrame.history();
          this.painted(frame, latencies);
        },
        pick: (result) => this.picked(result),
        eventError: (error) => this.eventFailed(error),
        stats: (stats) => {
          this.stats = stats;
          this.test.stats = {
            fps: stats.fps,
            bitrateBps: stats.bitrateBps,
            framesDropped: Number(stats.framesDropped),
          };
        },
        report: (message, severity) => this.report(message, severity),
        reopened: (opened) => this.reopened(opened),
        signedOut: (message) => this.signedOut(message),
        viewSize: () => this.viewSize(),
      });
    } catch (e) {
      if (open === this.opens) this.report(`cannot open ${file}: ${messageOf(e)}`, "error");
      return;
    }
    if (open !== this.opens) {
      await session.close();
      return;
    }
    this.session = session;
    if (file !== this.file) this.historyCracks = "";
    this.file = file;
    this.sentSize = size;
    this.panel.show(doc);
    this.shownPanelKey = "";
    ui.view.width = size.width;
    ui.view.height = size.height;
    const info = session.info;
    const first = Number(layer(doc, "data")?.getAttribute("step") ?? "0");
    this.live = { live: false, following: false, ended: false, steps: info.stepCount, lastStepAt: 0, plotAt: 0 };
    this.setStepRange(info.stepCount, first < 0 ? info.stepCount - 1 : first);
    ui.viewNote.hidden = true;
    document.title = `crackvis - ${file}`;
    const sizes = `N = ${info.particleCount}, M = ${info.bondCount}`;
    this.report(`opened ${file} (${info.stepCount} steps, ${sizes}; ${info.backend})`);
    ui.view.focus();
    let historyAsked = false;
    firstFrame.history = () => {
      // Not for a view replaced meanwhile (its timer still fires).
      if (historyAsked || this.session !== session) return;
      historyAsked = true;
      void this.showHistory(file);
    };
    window.setTimeout(firstFrame.history, kHistoryAfterMs);
  }

  private async closeSession(): Promise<void> {
    const session = this.session;
    this.session = null;
    if (session) await session.close();
  }

  private reopened(opened: OpenSessionResponse): void {
    this.report(`opened the view again as a new session (${opened.stepCount} steps)`, "warning");
  }

  // The series and the axis chosen stay chosen when the new history has them.
  private async showHistory(file: string): Promise<void> {
    try {
      const history = await api.stepHistory(file, this.historyCracks);
      if (file !== this.file) return; // another file opened meanwhile
      const names = this.plot.setHistory(history);
      this.test.brokenBonds = history.brokenBonds.map((b) => Number(b));
      const chosen = ui.plotScalar.value;
      const entries = names.map((name) => new Option(name, name));
      ui.plotScalar.replaceChildren(new Option("none", ""), ...entries);
      ui.plotScalar.value = names.includes(chosen) ? chosen : "";
      const against = ui.plotAxis.value;
      const axes = this.plot.axisNames();
      ui.plotAxis.replaceChildren(...axes.map((name) => new Option(name, name)));
      ui.plotAxis.value = axes.includes(against) ? against : "step";
      this.plot.setAxis(ui.plotAxis.value);
    } catch (e) {
      this.plot.setHistory(null);
      this.report(`no step plot for ${file}: ${messageOf(e)}`, "warning");
    }
  }

  // The crack's numbers of the panel's method over the file's steps, added
  // to the plot's series (the server computes them).
  private async addCrackNumbers(): Promise<void> {
    if (!this.file) {
      this.report("open a file first: the crack's numbers are the file's", "warning");
      return;
    }
    const method =
      layer(this.panel.description(), "cracks")?.getAttribute("method") ?? "local-voronoi";
    this.historyCracks = method;
    this.report(`computing the crack's numbers (${method}) over the steps of ${this.file} ...`);
    ui.crackNumbers.disabled = true;
    try {
      await this.showHistory(this.file);
    } finally {
      ui.crackNumbers.disabled = false;
    }
    if ([...ui.plotScalar.options].some((o) => o.value === "total_area")) {
      this.report(
        `the Steps plot has the crack's numbers (${method}): choose total_area, main_area, ` +
          "front_extent, fragments, ... and what to draw them against",
      );
    }
  }

  private send(body: Parameters<RenderSession["send"]>[0]): void {
    if (!this.session) return;
    this.test.lastEventId = Number(this.session.send(body));
  }

  // --- what the server sends

  private stateChanged(state: SessionState): void {
    this.test.state = {
      step: state.step,
      stepCount: state.stepCount,
      width: state.width,
      height: state.height,
      playing: state.playing,
      pipelineXml: state.pipelineXml,
    };
    // The canvas keeps the view's size; every frame is drawn scaled to it.
    const resized = ui.view.width !== state.width || ui.view.height !== state.height;
    if (state.width > 0 && state.height > 0 && resized) {
      ui.view.width = state.width;
      ui.view.height = state.height;
    }
    this.noteLive(state);
    this.setStepRange(state.stepCount, state.step);
    ui.play.textContent = state.playing ? "Pause" : "Play";
    this.showDescription(state.pipelineXml);
    this.showCrackWarning(state.crackWarning);
  }

  // The panel follows the description in force, but not every state (each
  // step while playing, each camera rest): only when its settings changed,
  // so that a field being edited is not overwritten.
  private showDescription(xml: string, force = false): void {
    if (!xml) return;
    let doc: XMLDocument;
    try {
      doc = parsePipeline(xml);
    } catch (e) {
      this.report(`the server's description: ${messageOf(e)}`, "error");
      return;
    }
    const file = fileOf(doc);
    if (file && file !== this.file) {
      // A replacement named another file (Open view).
      this.file = file;
      document.title = `crackvis - ${file}`;
      void this.describe(file);
      void this.showHistory(file);
    }
    const key = clonePipeline(doc);
    setData(key, file, 0);
    setViewSize(key, 16, 16);
    removeCamera(key);
    const keyText = serializePipeline(key);
    if (force || keyText !== this.shownPanelKey) {
      this.shownPanelKey = keyText;
      this.panel.show(doc);
    }
  }

  // Once per cause, as the Qt client: the numbers change with every step,
  // the cause follows the first ": ".
  private showCrackWarning(warning: string): void {
    const cause = warning.split(": ").slice(1).join(": ");
    if (warning && cause !== this.crackCause) this.report(`warning: ${warning}`, "warning");
    this.crackCause = cause;
  }

  private painted(frame: PaintedFrame, latencies: number[]): void {
    const t = this.test;
    t.framesPainted++;
    t.lastFrame = {
      step: frame.step,
      width: frame.width,
      height: frame.height,
      lastEventId: Number(frame.lastEventId),
      frameId: Number(frame.frameId),
      keyframe: frame.keyframe,
      fullResolution: frame.fullResolution,
    };
    for (const latency of latencies) {
      recent(this.latencies, latency);
      keep(t.latencies, latency);
    }
    recent(this.decodeMs, frame.decodeMs);
    keep(t.decodeMs, frame.decodeMs);
    t.paintedBy[frame.paintedBy]++;
    if (frame.serverMs > 0) keep(t.serverMs, frame.serverMs);
  }

  private picked(result: PickResult): void {
    this.test.lastPick = { kind: result.kind, index: Number(result.index), text: result.text };
    const text = result.kind ? result.text : "nothing there";
    ui.pick.textContent = `picked: ${text}`;
    this.report(`picked: ${text}`);
  }

  private eventFailed(error: EventError): void {
    this.report(`${error.message} (${api.statusName(error.code)})`, "error");
    // A refused replacement leaves the previous description in force.
    if (this.session?.state) this.showDescription(this.session.state.pipelineXml, true);
  }

  // --- the view

  private wireView(): void {
    attachViewInput(ui.view, {
      camera: (kind, dx, dy) => this.send({ case: "camera", value: { kind, dx, dy } }),
      still: () => this.send({ case: "still", value: {} }),
      pick: (x, y) => this.send({ case: "pick", value: { x, y } }),
      playToggled: () => this.togglePlay(),
      stepBy: (delta) => this.setStep(Number(ui.step.value) + delta),
    });
    new ResizeObserver(() => {
      clearTimeout(this.resizeTimer);
      this.resizeTimer = window.setTimeout(() => this.resized(), kResizeDebounceMs);
    }).observe(ui.viewport);
  }

  private resized(): void {
    const size = this.viewSize();
    const same = size.width === this.sentSize.width && size.height === this.sentSize.height;
    if (!this.session || same) return;
    this.sentSize = size;
    this.send({ case: "resize", value: size });
  }

  // --- the time bar

  private wireTimeBar(): void {
    ui.play.addEventListener("click", () => this.togglePlay());
    ui.step.addEventListener("pointerdown", () => (this.sliderHeld = true));
    ui.step.addEventListener("change", () => (this.sliderHeld = false));
    ui.step.addEventListener("input", () => this.setStep(Number(ui.step.value)));
    ui.follow.addEventListener("click", () => {
      if (this.live.following) {
        this.setStep(Number(ui.step.value));  // any step of one's own stops following
      } else {
        this.send({ case: "setStep", value: { step: -1, follow: true } });
      }
    });
    ui.plotScalar.addEventListener("change", () => this.plot.setScalar(ui.plotScalar.value));
    ui.plotAxis.addEventListener("change", () => this.plot.setAxis(ui.plotAxis.value));
    ui.crackNumbers.addEventListener("click", () => void this.addCrackNumbers());
  }

  // A live file's step count grew: when, and the Steps plot with the new
  // steps (read again at most every two seconds while steps pour in).
  private noteLive(state: SessionState): void {
    const now = performance.now();
    if (state.stepCount > this.live.steps && this.live.steps > 0) {
      this.live.lastStepAt = now;
      if (now - this.live.plotAt >= 2000 && this.file) {
        this.live.plotAt = now;
        void this.showHistory(this.file);
      }
    }
    this.live = {
      ...this.live,
      live: state.live,
      following: state.live && state.following,
      ended: state.runEnded,
      steps: state.stepCount,
    };
    ui.follow.disabled = !state.live;
    ui.follow.setAttribute("aria-pressed", String(this.live.following));
    this.showLive();
  }

  private showLive(): void {
    const { live, ended, lastStepAt } = this.live;
    if (live) {
      ui.live.textContent =
        lastStepAt > 0
          ? `live: last step ${Math.floor((performance.now() - lastStepAt) / 1000)} s ago`
          : "live";
    } else {
      ui.live.textContent = ended ? "run ended" : "";
    }
  }

  private setStepRange(stepCount: number, step: number): void {
    const last = Math.max(0, stepCount - 1);
    ui.step.max = String(last);
    if (!this.sliderHeld) ui.step.value = String(step);
    ui.stepLabel.textContent = `step ${step} / ${last}`;
    this.plot.setCurrentStep(step);
  }

  private setStep(step: number): void {
    if (!this.session) return;
    const last = Number(ui.step.max);
    const clamped = Math.min(last, Math.max(0, Math.round(step)));
    ui.step.value = String(clamped);
    ui.stepLabel.textContent = `step ${clamped} / ${last}`;
    this.send({ case: "setStep", value: { step: clamped } });
  }

  private togglePlay(): void {
    const state = this.session?.state;
    if (!state) return;
    const chosen = Number(ui.stepsPerSecond.value);
    const fps = Number.isFinite(chosen) && chosen > 0 ? chosen : 10;
    this.send({ case: "play", value: { playing: !state.playing, fps, loop: true } });
  }

  // --- screenshot, saved views, the panel

  private wireTools(): void {
    ui.screenshot.addEventListener("click", () => void this.screenshot());
    ui.saveView.addEventListener("click", () => this.saveView());
    ui.openView.addEventListener("click", () => ui.viewFile.click());
    ui.viewFile.addEventListener("change", () => void this.loadView());
    ui.fit.addEventListener("click", () =>
      this.send({ case: "camera", value: { kind: CameraEvent_Kind.RESET } }),
    );
  }

  private async snapshotPng(): Promise<Blob> {
    if (!this.session) throw new Error("no session");
    const shot = await api.snapshot(this.session.id);
    return new Blob([shot.png], { type: "image/png" });
  }

  private async screenshot(): Promise<void> {
    if (!this.session) {
      this.report("no view to take a screenshot of: open a file first", "warning");
      return;
    }
    try {
      const shot = await api.snapshot(this.session.id);
      const name = `${baseName(this.file)}-step${shot.step}.png`;
      download(shot.png, "image/png", name);
      this.report(`screenshot ${name} (${shot.width} x ${shot.height}, rendered by the server)`);
    } catch (e) {
      this.report(`screenshot: ${messageOf(e)}`, "error");
    }
  }

  // The description in force as the server reports it: the file, the step
  // shown, the panel's settings, the view's size and the camera where the
  // user left it (the Qt client's File > Save view).
  private saveView(): void {
    const xml = this.session?.description;
    if (!xml) {
      this.report("no view to save: open a file first", "warning");
      return;
    }
    download(xml, "application/xml", `${baseName(this.file)}-view.xml`);
    this.report("saved the view");
  }

  private async loadView(): Promise<void> {
    const chosen = ui.viewFile.files?.[0];
    ui.viewFile.value = "";
    if (!chosen) return;
    let doc: XMLDocument;
    try {
      doc = parsePipeline(await chosen.text());
    } catch (e) {
      this.report(`${chosen.name} is no view: ${messageOf(e)}`, "error");
      return;
    }
    const size = this.viewSize();
    setViewSize(doc, size.width, size.height);
    if (this.session) {
      this.send({ case: "replacePipeline", value: { pipelineXml: serializePipeline(doc) } });
      this.report(`loaded the view ${chosen.name}`);
    } else if (fileOf(doc)) {
      await this.openView(doc);
    } else {
      this.panel.show(doc);
      this.report(`loaded the view ${chosen.name}: it names no file, the next file opened uses it`);
    }
  }

  // The panel does not move the camera and keeps the step shown and the
  // view's size (the Qt client's panel).
  private panelChanged(doc: XMLDocument): void {
    if (!this.session) return;
    removeCamera(doc);
    setData(doc, this.file, Number(ui.step.value));
    setViewSize(doc, this.sentSize.width, this.sentSize.height);
    this.send({ case: "replacePipeline", value: { pipelineXml: serializePipeline(doc) } });
  }

  // --- the status line

  private showStatus(): void {
    this.showLive();
    if (!this.session) {
      ui.status.textContent = "";
      return;
    }
    const s = this.stats;
    const figure = (value: number, digits: number) =>
      Number.isNaN(value) ? "--" : value.toFixed(digits);
    const parts = [
      s ? `${s.fps.toFixed(0)} fps` : "-- fps",
      s ? `${(s.bitrateBps / 1e6).toFixed(2)} Mbit/s` : "-- Mbit/s",
      `latency ${figure(median(this.latencies), 0)} ms`,
      `decode ${figure(mean(this.decodeMs), 1)} ms`,
    ];
    if (s && s.framesDropped > 0n) parts.push(`${s.framesDropped} dropped`);
    ui.status.textContent = parts.join("   ");
  }

  // --- the test hook's faults

  private sendOversized(bytes: number): boolean {
    if (!this.session) return false;
    const event = create(ClientEventSchema, {
      eventId: 0n,
      event: { case: "replacePipeline", value: { pipelineXml: "x".repeat(bytes) } },
    });
    return this.session.sendRaw(toBinary(ClientEventSchema, event));
  }
}

new App().start();
