// Mouse, touch and keys on the view, turned into camera moves in view units
// (fractions of the view's width and height, x right, y down) as the Qt
// viewport sends them: left drag rotates, right, middle or shift + left drag
// pans, ctrl + left drag zooms (up zooms in), the wheel zooms; one finger
// rotates, two fingers pinch to zoom and move together to pan; a double
// click picks; `r` fits the specimen, space plays, arrow keys step.
import { CameraEvent_Kind } from "./gen/crackvis/v1/render_pb.js";

export interface ViewControls {
  camera(kind: CameraEvent_Kind, dx: number, dy: number): void;
  // A drag ended: the full-resolution picture now rather than after the
  // server's refine delay.
  still(): void;
  pick(x: number, y: number): void;
  playToggled(): void;
  stepBy(delta: number): void;
}

type Drag = CameraEvent_Kind.ROTATE | CameraEvent_Kind.PAN | CameraEvent_Kind.ZOOM;

interface Point {
  x: number;
  y: number;
}

// A wheel notch is 120 in Qt's angleDelta and zooms by exp(0.1); browsers
// report about 100 pixels a notch.
const kWheelPixelsPerUnit = 1000;
const kLinePixels = 40;
const kPagePixels = 800;

function dragOf(event: PointerEvent): Drag {
  if (event.button === 1 || event.button === 2 || event.shiftKey) return CameraEvent_Kind.PAN;
  if (event.ctrlKey || event.metaKey) return CameraEvent_Kind.ZOOM;
  return CameraEvent_Kind.ROTATE;
}

function wheelPixels(event: WheelEvent): number {
  const unit =
    event.deltaMode === WheelEvent.DOM_DELTA_LINE
      ? kLinePixels
      : event.deltaMode === WheelEvent.DOM_DELTA_PAGE
        ? kPagePixels
        : 1;
  return event.deltaY * unit;
}

function distance(a: Point, b: Point): number {
  return Math.hypot(a.x - b.x, a.y - b.y);
}

function middle(a: Point, b: Point): Point {
  return { x: (a.x + b.x) / 2, y: (a.y + b.y) / 2 };
}

// Moves are summed per kind and sent once per animation frame: a 120 Hz
// mouse, or a pinch that zooms and pans at once, would otherwise send
// events faster than frames can reflect them.
class MoveBatch {
  private readonly sums = new Map<CameraEvent_Kind, { dx: number; dy: number }>();
  private scheduled = false;

  constructor(private readonly controls: ViewControls) {}

  add(kind: CameraEvent_Kind, dx: number, dy: number): void {
    const sum = this.sums.get(kind) ?? { dx: 0, dy: 0 };
    sum.dx += dx;
    sum.dy += dy;
    this.sums.set(kind, sum);
    if (!this.scheduled) {
      this.scheduled = true;
      requestAnimationFrame(() => this.flush());
    }
  }

  flush(): void {
    this.scheduled = false;
    for (const [kind, { dx, dy }] of this.sums) {
      if (dx !== 0 || dy !== 0) this.controls.camera(kind, dx, dy);
    }
    this.sums.clear();
  }
}

export function attachViewInput(view: HTMLElement, controls: ViewControls): void {
  const batch = new MoveBatch(controls);
  const pointers = new Map<number, Point>();
  let drag: Drag = CameraEvent_Kind.ROTATE;
  let moved = false;

  const at = (event: PointerEvent | MouseEvent): Point => ({ x: event.offsetX, y: event.offsetY });
  const size = () => ({ w: Math.max(1, view.clientWidth), h: Math.max(1, view.clientHeight) });

  view.addEventListener("pointerdown", (event) => {
    view.focus();
    view.setPointerCapture(event.pointerId);
    pointers.set(event.pointerId, at(event));
    if (pointers.size === 1) {
      drag = event.pointerType === "mouse" ? dragOf(event) : CameraEvent_Kind.ROTATE;
    }
    moved = false;
    event.preventDefault();
  });

  view.addEventListener("pointermove", (event) => {
    const last = pointers.get(event.pointerId);
    if (!last) return;
    const now = at(event);
    const { w, h } = size();
    if (pointers.size >= 2) {
      const [other] = [...pointers].filter(([id]) => id !== event.pointerId).map(([, p]) => p);
      pinch(last, now, other, w, h);
    } else {
      const dx = (now.x - last.x) / w;
      const dy = (now.y - last.y) / h;
      if (drag === CameraEvent_Kind.ZOOM) batch.add(drag, -2 * dy, 0);
      else batch.add(drag, dx, dy);
    }
    pointers.set(event.pointerId, now);
    moved = true;
  });

  // Two fingers: the change of their distance zooms (exp(dx) = ratio), the
  // move of their middle pans.
  const pinch = (last: Point, now: Point, other: Point, w: number, h: number) => {
    const before = distance(last, other);
    const after = distance(now, other);
    if (before > 0 && after > 0) batch.add(CameraEvent_Kind.ZOOM, Math.log(after / before), 0);
    const m0 = middle(last, other);
    const m1 = middle(now, other);
    batch.add(CameraEvent_Kind.PAN, (m1.x - m0.x) / w, (m1.y - m0.y) / h);
  };

  const release = (event: PointerEvent) => {
    if (!pointers.delete(event.pointerId)) return;
    if (pointers.size > 0) return;
    batch.flush();
    if (moved) controls.still();
    moved = false;
  };
  view.addEventListener("pointerup", release);
  view.addEventListener("pointercancel", release);
  view.addEventListener("contextmenu", (event) => event.preventDefault());

  view.addEventListener(
    "wheel",
    (event) => {
      event.preventDefault();
      batch.add(CameraEvent_Kind.ZOOM, -wheelPixels(event) / kWheelPixelsPerUnit, 0);
    },
    { passive: false },
  );

  // The pixel's centre, as a fraction of the view from its top-left corner.
  view.addEventListener("dblclick", (event) => {
    const { w, h } = size();
    const p = at(event);
    controls.pick(Math.min(1, (p.x + 0.5) / w), Math.min(1, (p.y + 0.5) / h));
  });

  view.addEventListener("keydown", (event) => {
    if (event.ctrlKey || event.altKey || event.metaKey) return;
    switch (event.key) {
      case "r":
      case "R":
        controls.camera(CameraEvent_Kind.RESET, 0, 0);
        break;
      case " ":
        controls.playToggled();
        break;
      case "ArrowRight":
      case "ArrowUp":
        controls.stepBy(1);
        break;
      case "ArrowLeft":
      case "ArrowDown":
        controls.stepBy(-1);
        break;
      default:
        return;
    }
    event.preventDefault();
  });
}
