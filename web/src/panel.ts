// The pipeline panel, as the Qt client's pipeline_panel.cpp: crack
// surfaces (method and its options, components, colour), particles,
// bonds and decomposition, one clipping plane that each layer may be cut by,
// a colour range and a threshold per layer, and the view and stream. It
// shows a description (show) and, when a control changes, hands the edited
// copy to `changed`; it never edits what it was given. Attributes it has no
// control for (the camera, the client layout) stay as they were.
import { el } from "./dom.js";
import {
  clonePipeline,
  childOf,
  ensureChild,
  ensureLayer,
  initialPipeline,
  layer,
  removeChild,
  serializePipeline,
} from "./pipeline_xml.js";

type Control = HTMLInputElement | HTMLSelectElement;
type Kind = "check" | "select" | "number" | "colour";
type Options = ReadonlyArray<readonly [label: string, value: string]>;

// One control bound to one attribute of one of <pipeline>'s children.
interface Field {
  layer: string;
  attribute: string;
  fallback: string; // the schema's default
  kind: Kind;
  control: Control;
  scale: number; // shown = stored / scale (bitrate in kbit/s)
}

// A layer's colour range, clip switch and threshold.
interface LayerControls {
  rangeMode: HTMLSelectElement;
  rangeMin: HTMLInputElement;
  rangeMax: HTMLInputElement;
  clip: HTMLInputElement;
  threshold: HTMLInputElement;
  thresholdBy: HTMLSelectElement;
  thresholdMin: HTMLInputElement;
  thresholdMax: HTMLInputElement;
}

type LayerName = "particles" | "cracks" | "bonds";
const kLayers: readonly LayerName[] = ["particles", "cracks", "bonds"];

const kMethods: Options = [
  ["local Voronoi", "local-voronoi"],
  ["cell cut", "cell-cut"],
  ["cell centre", "cell-centre"],
  ["cell attribute", "cell-attribute"],
];
const kDecompositions: Options = [
  ["auto", "auto"],
  ["lattice cells", "lattice"],
  ["triangulation", "triangulation"],
];
const kCrackColourBy: Options = [
  ["solid", "solid"],
  ["bond id", "bond-id"],
  ["force", "force"],
  ["break step", "break-step"],
  ["state", "state"],
  ["component", "component"],
  ["opening", "opening"],
  ["slip", "slip"],
];
const kParticleColourBy: Options = [
  ["solid", "solid"],
  ["radius", "radius"],
  ["displacement", "displacement"],
  ["velocity", "velocity"],
  ["damage", "damage"],
  ["fragment", "fragment"],
];
const kBondColourBy: Options = [
  ["state", "state"],
  ["solid", "solid"],
  ["force", "force"],
  ["break step", "break-step"],
];
const kRepresentations: Options = [
  ["sphere impostors", "impostors"],
  ["points", "points"],
];
const kBondSelections: Options = [
  ["none", "none"],
  ["broken", "broken"],
  ["all", "all"],
];
const kBondRepresentations: Options = [
  ["lines", "lines"],
  ["tubes", "tubes"],
];
const kColourMaps: Options = [
  ["viridis", "viridis"],
  ["cool to warm", "cool-warm"],
  ["rainbow", "rainbow"],
  ["grayscale", "grayscale"],
];
const kRangeModes: Options = [
  ["per step", "step"],
  ["over all steps", "series"],
  ["set", "user"],
];
// Extra arrays of the file: entries "extra: NAME" with the value "extra:NAME".
const kExtraLabel = "extra: ";
const kExtraValue = "extra:";

function options(box: HTMLSelectElement, entries: Options): HTMLSelectElement {
  for (const [label, value] of entries) box.append(el("option", { value, text: label }));
  return box;
}

function numberInput(min: number, max: number, step: number): HTMLInputElement {
  return el("input", { type: "number", min: String(min), max: String(max), step: String(step) });
}

function hasOption(box: HTMLSelectElement, value: string): boolean {
  return Array.from(box.options).some((option) => option.value === value);
}

// A value the list lacks (an extra array of another file) is added, so
// that showing a description never changes it.
function selectValue(box: HTMLSelectElement, value: string): void {
  if (!hasOption(box, value)) {
    const extra = value.startsWith(kExtraValue);
    const label = extra ? kExtraLabel + value.slice(kExtraValue.length) : value;
    box.append(el("option", { value, text: label }));
  }
  box.value = value;
}

function isTrue(text: string): boolean {
  return text === "true" || text === "1";
}

// The field's number within the control's limits, or null when it holds none.
function numberIn(input: HTMLInputElement): number | null {
  if (input.value.trim() === "") return null;
  let value = Number(input.value);
  if (!Number.isFinite(value)) return null;
  if (input.min !== "") value = Math.max(Number(input.min), value);
  if (input.max !== "") value = Math.min(Number(input.max), value);
  return input.step === "1" ? Math.round(value) : value;
}

function numberText(value: string | null): string {
  const number = Number(value);
  return value !== null && value !== "" && Number.isFinite(number) ? String(number) : "";
}

function vec3(text: string | null, fallback: number[]): number[] {
  const values = (text ?? "").trim().split(/\s+/).map(Number);
  return values.length === 3 && values.every(Number.isFinite) ? values : fallback;
}

export class PipelinePanel {
  private doc: XMLDocument = initialPipeline();
  private readonly fields: Field[] = [];
  private readonly layerControls = {} as Record<LayerName, LayerControls>;
  private readonly planeOrigin: HTMLInputElement[] = [];
  private readonly planeNormal: HTMLInputElement[] = [];
  private readonly colourBy = {} as Record<LayerName, HTMLSelectElement>;
  // Controls typed into but not yet committed (no change event yet): a
  // state arriving meanwhile must not overwrite what the user is typing.
  private readonly editing = new Set<EventTarget>();
  // Layers whose threshold is switched on with neither end given yet: the
  // schema wants one, so nothing is sent until the user gives it.
  private readonly pendingThreshold = new Set<LayerName>();

  constructor(
    root: HTMLElement,
    private readonly changed: (doc: XMLDocument) => void,
  ) {
    root.append(
      this.crackGroup(),
      this.particleGroup(),
      this.bondGroup(),
      this.planeGroup(),
      this.viewGroup(),
    );
    root.addEventListener("input", (event) => {
      if (event.target) this.editing.add(event.target);
    });
    root.addEventListener("change", () => this.collect());
    this.show(this.doc);
  }

  // A copy of the description the panel shows, with its edits.
  description(): XMLDocument {
    return clonePipeline(this.doc);
  }

  show(doc: XMLDocument): void {
    this.doc = clonePipeline(doc);
    for (const field of this.fields) this.showField(field);
    for (const name of kLayers) this.showLayer(name);
    this.showPlane();
  }

  // The file's extra arrays as colour-by and threshold entries.
  setExtras(particleNames: string[], bondNames: string[]): void {
    const replace = (box: HTMLSelectElement, names: string[]) => {
      for (const option of Array.from(box.options)) {
        if (option.value.startsWith(kExtraValue)) option.remove();
      }
      for (const name of names) {
        box.append(el("option", { value: kExtraValue + name, text: kExtraLabel + name }));
      }
    };
    replace(this.colourBy.particles, particleNames);
    replace(this.colourBy.bonds, bondNames);
    replace(this.layerControls.particles.thresholdBy, particleNames);
    replace(this.layerControls.bonds.thresholdBy, bondNames);
    this.show(this.doc);
  }

  // --- building the controls

  // A control bound to <layer attribute="..."> (its id: layer-attribute).
  private field<C extends Control>(
    layerName: string,
    attribute: string,
    fallback: string,
    kind: Kind,
    control: C,
    scale = 1,
  ): C {
    control.id = `${layerName}-${attribute}`;
    this.fields.push({ layer: layerName, attribute, fallback, kind, control, scale });
    return control;
  }

  private check(layerName: string, attribute: string, fallback: string, label: string) {
    const box = el("input", { type: "checkbox" });
    this.field(layerName, attribute, fallback, "check", box);
    return el("label", { className: "check" }, box, label);
  }

  private choice(layerName: string, attribute: string, fallback: string, entries: Options) {
    return this.field(layerName, attribute, fallback, "select", options(el("select"), entries));
  }

  // [min, max] in steps of `step`, shown divided by `scale`.
  private number(
    layerName: string,
    attribute: string,
    fallback: string,
    [min, max, step]: [number, number, number],
    scale = 1,
  ) {
    const input = numberInput(min, max, step);
    return this.field(layerName, attribute, fallback, "number", input, scale);
  }

  private colour(layerName: string, attribute: string, fallback: string) {
    return this.field(layerName, attribute, fallback, "colour", el("input", { type: "color" }));
  }

  private row(label: string, ...controls: HTMLElement[]): HTMLElement {
    return el("div", { className: "row" }, el("span", { textContent: label }), ...controls);
  }

  private group(title: string, ...rows: HTMLElement[]): HTMLElement {
    return el("fieldset", {}, el("legend", { textContent: title }), ...rows);
  }

  private crackGroup(): HTMLElement {
    this.colourBy.cracks = this.choice("cracks", "colour-by", "solid", kCrackColourBy);
    return this.group(
      "Crack surfaces",
      this.check("cracks", "visible", "true", "visible"),
      this.row("method", this.choice("cracks", "method", "local-voronoi", kMethods)),
      this.check("cracks", "validation", "true", "validate (empty-sphere test)"),
      this.row("tolerance", this.number("cracks", "validation-tolerance", "0.1", [0, 1, 0.05])),
      this.check("cracks", "merge-octahedra", "false", "merge octahedra (cell centre)"),
      this.row("cells", this.choice("cracks", "decomposition", "auto", kDecompositions)),
      this.row("largest components", this.number("cracks", "largest", "0", [0, 1e6, 1])),
      this.row("smallest (m²)", this.number("cracks", "min-component", "0", [0, 1e12, 1e-6])),
      this.row("colour by", this.colourBy.cracks, this.colour("cracks", "colour", "#e03c31")),
      this.row("opacity", this.number("cracks", "opacity", "1", [0, 1, 0.1])),
      ...this.layerRows("cracks"),
    );
  }

  private particleGroup(): HTMLElement {
    this.colourBy.particles = this.choice("particles", "colour-by", "solid", kParticleColourBy);
    const shape = this.choice("particles", "representation", "impostors", kRepresentations);
    return this.group(
      "Particles",
      this.check("particles", "visible", "true", "visible"),
      this.row("representation", shape),
      this.row("colour by", this.colourBy.particles, this.colour("particles", "colour", "#b0b0b0")),
      this.row("opacity", this.number("particles", "opacity", "1", [0, 1, 0.1])),
      ...this.layerRows("particles"),
    );
  }

  private bondGroup(): HTMLElement {
    this.colourBy.bonds = this.choice("bonds", "colour-by", "state", kBondColourBy);
    return this.group(
      "Bonds and decomposition",
      this.row("show", this.choice("bonds", "show", "none", kBondSelections)),
      this.row("as", this.choice("bonds", "representation", "lines", kBondRepresentations)),
      this.row("colour by", this.colourBy.bonds, this.colour("bonds", "colour", "#404040")),
      this.row("tube radius", this.number("bonds", "tube-radius", "0.15", [0.01, 1, 0.05])),
      ...this.layerRows("bonds"),
      this.check("decomposition", "show", "false", "show the local decomposition"),
      this.check("inconsistent", "show", "false", "mark inconsistent bonds"),
    );
  }

  private planeGroup(): HTMLElement {
    const boxes = (range: [number, number, number], list: HTMLInputElement[], name: string) =>
      ["x", "y", "z"].map((axis) => {
        const input = numberInput(...range);
        input.id = `clip-${name}-${axis}`;
        list.push(input);
        return input;
      });
    return this.group(
      "Clipping plane (hides the side the normal points to)",
      this.row("origin (m)", ...boxes([-1e6, 1e6, 0.005], this.planeOrigin, "origin")),
      this.row("normal", ...boxes([-1, 1, 0.1], this.planeNormal, "normal")),
      el("p", {
        className: "hint",
        textContent: 'Cuts each layer whose "cut by the clipping plane" is on.',
      }),
    );
  }

  private viewGroup(): HTMLElement {
    return this.group(
      "View and stream",
      this.row("background", this.colour("view", "background", "#1e1e28")),
      this.row("colour map", this.choice("view", "colour-map", "viridis", kColourMaps)),
      this.check("view", "scalar-bar", "true", "scalar bars"),
      this.check("annotations", "show", "true", "annotations (step, time, method, axes, scale)"),
      this.row("stream fps", this.number("stream", "fps", "30", [1, 120, 1])),
      this.row("kbit/s", this.number("stream", "bitrate", "4000000", [100, 1e5, 100], 1000)),
    );
  }

  // The range editor, clip switch and threshold row of one layer.
  private layerRows(name: LayerName): HTMLElement[] {
    const field = (placeholder: string, id: string, title = "") =>
      el("input", { type: "number", step: "any", placeholder, title, id: `${name}-${id}` });
    const c: LayerControls = {
      rangeMode: options(el("select", { id: `${name}-range` }), kRangeModes),
      rangeMin: field("min", "range-min"),
      rangeMax: field("max", "range-max"),
      clip: el("input", { type: "checkbox", id: `${name}-clip` }),
      threshold: el("input", { type: "checkbox", id: `${name}-threshold` }),
      thresholdBy: el("select", { id: `${name}-threshold-by` }),
      thresholdMin: field("from", "threshold-min", "empty: no lower end"),
      thresholdMax: field("to", "threshold-max", "empty: no upper end"),
    };
    // The quantities a threshold can keep: the layer's colour-by ones but solid.
    for (const option of Array.from(this.colourBy[name].options)) {
      if (option.value === "solid") continue;
      c.thresholdBy.append(el("option", { value: option.value, text: option.text }));
    }
    this.layerControls[name] = c;
    const thresholdSwitch = el("label", { className: "check" }, c.threshold, "threshold");
    const thresholdRow = [thresholdSwitch, c.thresholdBy, c.thresholdMin, c.thresholdMax];
    return [
      this.row("colour range", c.rangeMode, c.rangeMin, c.rangeMax),
      el("label", { className: "check" }, c.clip, "cut by the clipping plane"),
      el("div", { className: "row" }, ...thresholdRow),
    ];
  }

  // --- description -> controls

  private showField(f: Field): void {
    const value = layer(this.doc, f.layer)?.getAttribute(f.attribute) ?? f.fallback;
    const control = f.control;
    if (this.editing.has(control)) return;
    if (f.kind === "check") (control as HTMLInputElement).checked = isTrue(value);
    else if (f.kind === "select") selectValue(control as HTMLSelectElement, value);
    else if (f.kind === "colour") control.value = value.toLowerCase();
    else control.value = numberText(String(Number(value) / f.scale));
  }

  private showLayer(name: LayerName): void {
    const c = this.layerControls[name];
    const element = layer(this.doc, name);
    const mode = element?.getAttribute("range") ?? "step";
    const user = mode === "user";
    const threshold = element ? childOf(element, "threshold") : null;
    this.showValue(c.rangeMode, mode);
    this.showValue(c.rangeMin, user ? numberText(element!.getAttribute("range-min")) : "");
    this.showValue(c.rangeMax, user ? numberText(element!.getAttribute("range-max")) : "");
    c.clip.checked = element !== null && childOf(element, "clip") !== null;
    c.threshold.checked = threshold !== null || this.pendingThreshold.has(name);
    if (threshold) {
      const by = threshold.getAttribute("by") ?? "";
      if (!this.editing.has(c.thresholdBy)) selectValue(c.thresholdBy, by);
      this.showValue(c.thresholdMin, numberText(threshold.getAttribute("min")));
      this.showValue(c.thresholdMax, numberText(threshold.getAttribute("max")));
    }
  }

  private showValue(control: Control, value: string): void {
    if (!this.editing.has(control)) control.value = value;
  }

  // One plane in the panel: the first layer's that has one.
  private showPlane(): void {
    const clip = kLayers
      .map((name) => layer(this.doc, name))
      .map((element) => (element ? childOf(element, "clip") : null))
      .find((found) => found !== null);
    const origin = vec3(clip?.getAttribute("origin") ?? null, [0, 0, 0]);
    const normal = vec3(clip?.getAttribute("normal") ?? null, [1, 0, 0]);
    origin.forEach((v, k) => this.showValue(this.planeOrigin[k], String(v)));
    normal.forEach((v, k) => this.showValue(this.planeNormal[k], String(v)));
  }

  // --- controls -> description

  private collect(): void {
    this.editing.clear(); // every control's value goes into the description now
    const doc = clonePipeline(this.doc);
    for (const field of this.fields) this.collectField(doc, field);
    for (const name of kLayers) this.collectLayer(doc, name);
    if (serializePipeline(doc) === serializePipeline(this.doc)) return;
    this.doc = doc;
    this.changed(clonePipeline(doc));
  }

  private collectField(doc: XMLDocument, f: Field): void {
    const element = ensureLayer(doc, f.layer);
    const control = f.control;
    if (f.kind === "check") {
      element.setAttribute(f.attribute, String((control as HTMLInputElement).checked));
    } else if (f.kind === "number") {
      const value = numberIn(control as HTMLInputElement);
      // An empty or unreadable field keeps the value in force; the rounding
      // drops binary noise from the scale (2000 kbit/s is 2000000, not 1999999.9999).
      const stored = value === null ? null : Math.round(value * f.scale * 1e9) / 1e9;
      if (stored !== null) element.setAttribute(f.attribute, String(stored));
    } else {
      element.setAttribute(f.attribute, control.value);
    }
  }

  private collectLayer(doc: XMLDocument, name: LayerName): void {
    const c = this.layerControls[name];
    const element = ensureLayer(doc, name);
    element.setAttribute("range", c.rangeMode.value);
    if (c.rangeMode.value === "user") {
      const min = numberIn(c.rangeMin) ?? 0;
      const max = numberIn(c.rangeMax) ?? min + 1;
      element.setAttribute("range-min", String(min));
      element.setAttribute("range-max", String(max));
    } else {
      element.removeAttribute("range-min");
      element.removeAttribute("range-max");
    }
    if (c.clip.checked) {
      const clip = ensureChild(element, "clip");
      clip.setAttribute("origin", this.planeOrigin.map((i) => numberIn(i) ?? 0).join(" "));
      clip.setAttribute("normal", this.planeNormal.map((i) => numberIn(i) ?? 0).join(" "));
    } else {
      removeChild(element, "clip");
    }
    const min = numberIn(c.thresholdMin);
    const max = numberIn(c.thresholdMax);
    this.pendingThreshold.delete(name);
    if (!c.threshold.checked || c.thresholdBy.options.length === 0) {
      removeChild(element, "threshold");
    } else if (min === null && max === null) {
      this.pendingThreshold.add(name);
      removeChild(element, "threshold");
    } else {
      const threshold = ensureChild(element, "threshold");
      threshold.setAttribute("by", c.thresholdBy.value);
      // An end left empty is open.
      if (min === null) threshold.removeAttribute("min");
      else threshold.setAttribute("min", String(min));
      if (max === null) threshold.removeAttribute("max");
      else threshold.setAttribute("max", String(max));
    }
  }
}
