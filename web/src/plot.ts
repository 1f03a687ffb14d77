// The Steps plot, as the Qt client's step_plot.cpp draws it: broken bonds
// on the left axis, optionally one series (a step scalar such as the load,
// or a crack number such as total_area) on the right axis, against the
// step or against any other series (the crack area against the load), and
// the step shown as a dashed line. A click or drag on it goes to the step
// nearest along the horizontal axis.
import type { StepHistoryResponse } from "./gen/crackvis/v1/render_pb.js";

const kBroken = "#ff9f1c";
const kScalar = "#4cc9f0";
const kBackground = "#1e1e28";
const kText = "#d0d0d0";
// Plot area inside the canvas: room for the value labels left and right,
// the title above and the step axis below (CSS pixels).
const kMargin = { left: 64, right: 64, top: 22, bottom: 26 };

interface Area {
  left: number;
  top: number;
  width: number;
  height: number;
}

// The finite values' range, widened when all are equal (0..1 without any).
function rangeOf(values: readonly number[]): [number, number] {
  let lo = Infinity;
  let hi = -Infinity;
  for (const v of values) {
    if (Number.isFinite(v)) {
      lo = Math.min(lo, v);
      hi = Math.max(hi, v);
    }
  }
  if (!(lo <= hi)) return [0, 1];
  return lo === hi ? [lo - 0.5, hi + 0.5] : [lo, hi];
}

// Counts in full ("17653", not "1.765e+04"); other values with four digits.
function label(value: number): string {
  if (Number.isInteger(value) && Math.abs(value) < 1e7) return String(value);
  return value.toPrecision(4).replace(/\.?0+(e|$)/, "$1");
}

// The horizontal axis's names beside the series'.
const kStepAxis = "step";
const kTimeAxis = "time";
const kBrokenAxis = "broken bonds";

export class StepPlot {
  private history: StepHistoryResponse | null = null;
  private scalar = -1;
  private axis = ""; // "" the step
  private step = -1;
  private readonly context: CanvasRenderingContext2D;

  constructor(
    private readonly canvas: HTMLCanvasElement,
    private readonly stepClicked: (step: number) => void,
  ) {
    const context = canvas.getContext("2d");
    if (!context) throw new Error("no 2D canvas context");
    this.context = context;
    const goTo = (event: PointerEvent) => {
      const step = this.stepAt(event.offsetX);
      if (step >= 0) this.stepClicked(step);
    };
    canvas.addEventListener("pointerdown", (event) => {
      canvas.setPointerCapture(event.pointerId);
      goTo(event);
    });
    canvas.addEventListener("pointermove", (event) => {
      if (event.buttons & 1) goTo(event);
    });
    new ResizeObserver(() => this.draw()).observe(canvas);
  }

  // Names of the file's step scalars, for the page's choice of the second curve.
  setHistory(history: StepHistoryResponse | null): string[] {
    const chosen = this.scalarName();
    const against = this.axisName();
    this.history = history;
    this.scalar = -1;
    if (chosen) this.setScalar(chosen);
    this.setAxis(against);
    this.draw();
    return history ? history.scalars.map((s) => s.name) : [];
  }

  // What the horizontal axis shows: "step", "time", "broken bonds" or a
  // series' name; false (the step) for a name the history lacks.
  setAxis(name: string): boolean {
    const known = name !== kStepAxis && this.axisNames().includes(name);
    this.axis = known ? name : "";
    this.draw();
    return known || name === "" || name === kStepAxis;
  }

  axisName(): string {
    return this.axis || kStepAxis;
  }

  // The names setAxis() takes for the history shown.
  axisNames(): string[] {
    if (!this.history) return [kStepAxis];
    const names = [kStepAxis];
    if (this.history.time.length > 0) names.push(kTimeAxis);
    names.push(kBrokenAxis, ...this.history.scalars.map((s) => s.name));
    return names;
  }

  // Each step's value on the horizontal axis (NaN where it has none).
  private axisValues(): number[] {
    const h = this.history;
    if (!h) return [];
    const steps = this.steps();
    const series = h.scalars.find((s) => s.name === this.axis);
    return Array.from({ length: steps }, (_, k) => {
      if (this.axis === "") return k;
      if (this.axis === kTimeAxis) return k < h.time.length ? h.time[k] : NaN;
      if (this.axis === kBrokenAxis) return Number(h.brokenBonds[k]);
      return series && k < series.values.length ? series.values[k] : NaN;
    });
  }

  setScalar(name: string): void {
    this.scalar = this.history ? this.history.scalars.findIndex((s) => s.name === name) : -1;
    this.draw();
  }

  setCurrentStep(step: number): void {
    if (step === this.step) return;
    this.step = step;
    this.draw();
  }

  private scalarName(): string {
    return this.history && this.scalar >= 0 ? this.history.scalars[this.scalar].name : "";
  }

  private steps(): number {
    return this.history ? this.history.brokenBonds.length : 0;
  }

  private area(): Area {
    return {
      left: kMargin.left,
      top: kMargin.top,
      width: this.canvas.clientWidth - kMargin.left - kMargin.right,
      height: this.canvas.clientHeight - kMargin.top - kMargin.bottom,
    };
  }

  // The x of each step (NaN where the axis has no value).
  private xs(area: Area): number[] {
    const values = this.axisValues();
    const [lo, hi] = rangeOf(values);
    return values.map((v) => area.left + ((v - lo) / (hi - lo)) * area.width);
  }

  // The step nearest along the axis; of equally near ones (a load that
  // falls back to a value it had), the one nearest the step shown.
  private stepAt(x: number): number {
    const steps = this.steps();
    if (steps === 0) return -1;
    const area = this.area();
    if (steps === 1 || area.width <= 0) return 0;
    const values = this.axisValues();
    const [lo, hi] = rangeOf(values);
    const wanted = lo + Math.min(1, Math.max(0, (x - area.left) / area.width)) * (hi - lo);
    let best = -1;
    for (let k = 0; k < steps; k++) {
      if (!Number.isFinite(values[k])) continue;
      const distance = Math.abs(values[k] - wanted);
      const bestDistance = best < 0 ? Infinity : Math.abs(values[best] - wanted);
      if (
        distance < bestDistance ||
        (distance === bestDistance && Math.abs(k - this.step) < Math.abs(best - this.step))
      ) {
        best = k;
      }
    }
    return Math.max(best, 0);
  }

  // The backing store follows the element's size and the screen's pixel
  // ratio, so lines stay sharp; drawing happens in CSS pixels.
  private draw(): void {
    const ratio = window.devicePixelRatio || 1;
    const cssWidth = this.canvas.clientWidth;
    const cssHeight = this.canvas.clientHeight;
    this.canvas.width = Math.max(1, Math.round(cssWidth * ratio));
    this.canvas.height = Math.max(1, Math.round(cssHeight * ratio));
    const g = this.context;
    g.setTransform(ratio, 0, 0, ratio, 0, 0);
    g.fillStyle = kBackground;
    g.fillRect(0, 0, cssWidth, cssHeight);
    g.font = "12px sans-serif";
    const area = this.area();
    const steps = this.steps();
    if (!this.history || steps === 0 || area.width <= 0 || area.height <= 0) {
      g.fillStyle = kText;
      g.textAlign = "center";
      g.fillText("Open a file to see its steps", cssWidth / 2, cssHeight / 2);
      return;
    }
    g.strokeStyle = kText;
    g.lineWidth = 1;
    g.strokeRect(area.left, area.top, area.width, area.height);
    this.drawAxis(area, steps);
    const xs = this.xs(area);
    const broken = this.history.brokenBonds.map((b) => Number(b));
    this.curve(broken, kBroken, true, area, xs);
    g.fillStyle = kBroken;
    g.textAlign = "left";
    g.fillText(`broken bonds (of ${this.history.bondCount})`, area.left, 14);
    if (this.scalar >= 0) {
      const series = this.history.scalars[this.scalar];
      this.curve(series.values, kScalar, false, area, xs);
      g.fillStyle = kScalar;
      g.textAlign = "right";
      g.fillText(series.name, area.left + area.width, 14);
    }
    if (this.step >= 0 && this.step < steps && Number.isFinite(xs[this.step])) {
      const x = xs[this.step];
      g.strokeStyle = "#ffffff";
      g.setLineDash([4, 3]);
      g.beginPath();
      g.moveTo(x, area.top);
      g.lineTo(x, area.top + area.height);
      g.stroke();
      g.setLineDash([]);
    }
  }

  // The ends of the step axis with their simulated times, or another
  // axis's range and name.
  private drawAxis(area: Area, steps: number): void {
    const g = this.context;
    const time = this.history!.time;
    const end = (step: number) =>
      step < time.length ? `${step} (t = ${label(time[step])} s)` : String(step);
    const [lo, hi] = rangeOf(this.axisValues());
    const ends = this.axis === "" ? [end(0), end(steps - 1)] : [label(lo), label(hi)];
    const y = area.top + area.height + 16;
    g.fillStyle = kText;
    g.textAlign = "left";
    g.fillText(ends[0], area.left, y);
    // The axis's name where the ends' labels leave room for it.
    if (area.width > 360 || this.axis !== "") {
      g.textAlign = "center";
      g.fillText(this.axisName(), area.left + area.width / 2, y);
    }
    g.textAlign = "right";
    g.fillText(ends[1], area.left + area.width, y);
  }

  // A step without the value (NaN) breaks the line.
  private curve(
    values: readonly number[],
    colour: string,
    left: boolean,
    area: Area,
    xs: readonly number[],
  ): void {
    const g = this.context;
    const [lo, hi] = rangeOf(values);
    g.strokeStyle = colour;
    g.lineWidth = 2;
    g.beginPath();
    let open = false;
    const steps = Math.min(this.steps(), values.length);
    for (let k = 0; k < steps; k++) {
      const v = values[k];
      if (!Number.isFinite(v) || !Number.isFinite(xs[k])) {
        open = false;
        continue;
      }
      const x = xs[k];
      const y = area.top + area.height - ((v - lo) / (hi - lo)) * area.height;
      if (open) g.lineTo(x, y);
      else g.moveTo(x, y);
      open = true;
    }
    g.stroke();
    g.fillStyle = kText;
    g.textAlign = left ? "right" : "left";
    const x = left ? area.left - 4 : area.left + area.width + 4;
    g.fillText(label(hi), x, area.top + 4);
    g.fillText(label(lo), x, area.top + area.height);
  }
}
