// The messages pane: one line per message, newest last, as text. A message
// that repeats the last one (a failing step while playing, a reconnect
// loop) updates that line with a count instead of flooding the pane, as the
// Qt client's does.
import { el } from "./dom.js";

const kMaxLines = 500;

export type Severity = "info" | "warning" | "error";

export class MessageLog {
  private last = "";
  private repeats = 0;

  constructor(
    private readonly pane: HTMLElement,
    private readonly latest: HTMLElement,
  ) {}

  report(message: string, severity: Severity = "info"): void {
    this.latest.textContent = message;
    this.latest.className = severity;
    const time = new Date().toLocaleTimeString();
    const line = this.pane.lastElementChild;
    if (message === this.last && line) {
      this.repeats++;
      line.textContent = `${time}  ${message} (${this.repeats + 1} times)`;
      return;
    }
    this.last = message;
    this.repeats = 0;
    this.pane.append(el("div", { className: severity, textContent: `${time}  ${message}` }));
    while (this.pane.childElementCount > kMaxLines) this.pane.firstElementChild?.remove();
    this.pane.scrollTop = this.pane.scrollHeight;
  }
}
