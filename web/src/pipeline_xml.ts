// Pipeline descriptions (docs/pipeline.md, pipeline-schemas/pipeline.xsd)
// as DOM documents: the page's first description, reading one the server
// or a file gave, the edits the page makes before sending one (file, step,
// the view's size, the camera) and writing it back out. The server
// validates every document; these helpers only keep the schema's element
// order, so an element the page adds lands where the schema wants it.

// The schema's order of <pipeline>'s children.
const kOrder = [
  "data",
  "particles",
  "cracks",
  "bonds",
  "decomposition",
  "inconsistent",
  "view",
  "annotations",
  "stream",
  "client",
];

// The Qt client's first description: every attribute at the schema's
// default, written out so that the panel shows what is in force. File and
// view size are filled in when a file is opened.
const kInitial = `<?xml version="1.0" encoding="UTF-8"?>
<pipeline version="1">
  <data file="" step="-1"/>
  <particles visible="true" representation="impostors" colour-by="solid" colour="#b0b0b0"
             opacity="1" range="step"/>
  <cracks visible="true" method="local-voronoi" validation="true" validation-tolerance="0.1"
          merge-octahedra="false" decomposition="auto" largest="0" min-component="0"
          colour-by="solid" colour="#e03c31" opacity="1" range="step"/>
  <bonds show="none" representation="lines" colour-by="state" colour="#404040" tube-radius="0.15"
         range="step"/>
  <decomposition show="false"/>
  <inconsistent show="false"/>
  <view width="1280" height="720" background="#1e1e28" colour-map="viridis" scalar-bar="true"/>
  <annotations show="true" time="true" method="true" axes="true" scale-bar="true"/>
  <stream fps="30" bitrate="4000000"/>
</pipeline>
`;

export class PipelineError extends Error {}

export function initialPipeline(): XMLDocument {
  return parsePipeline(kInitial);
}

// A document with a <pipeline> root; a syntax error names what the parser said.
export function parsePipeline(text: string): XMLDocument {
  const doc = new DOMParser().parseFromString(text, "application/xml");
  const error = doc.getElementsByTagName("parsererror")[0];
  if (error) {
    const said = (error.textContent ?? "").trim().split("\n")[0];
    throw new PipelineError(`not well-formed XML: ${said}`);
  }
  if (doc.documentElement.localName !== "pipeline") {
    const root = doc.documentElement.localName;
    throw new PipelineError(`the document's root is <${root}>, not <pipeline>`);
  }
  return doc;
}

export function serializePipeline(doc: XMLDocument): string {
  return new XMLSerializer().serializeToString(doc);
}

export function clonePipeline(doc: XMLDocument): XMLDocument {
  return doc.cloneNode(true) as XMLDocument;
}

// <pipeline>'s child `name`, or null.
export function layer(doc: XMLDocument, name: string): Element | null {
  for (const child of Array.from(doc.documentElement.children)) {
    if (child.localName === name) return child;
  }
  return null;
}

// <pipeline>'s child `name`, created in the schema's order when missing.
export function ensureLayer(doc: XMLDocument, name: string): Element {
  const existing = layer(doc, name);
  if (existing) return existing;
  const created = doc.createElementNS(null, name);
  const rank = kOrder.indexOf(name);
  const before = Array.from(doc.documentElement.children).find(
    (child) => kOrder.indexOf(child.localName) > rank,
  );
  doc.documentElement.insertBefore(created, before ?? null);
  return created;
}

// A layer's child `name` (clip, threshold, camera), or null.
export function childOf(parent: Element, name: string): Element | null {
  return Array.from(parent.children).find((child) => child.localName === name) ?? null;
}

// A layer's child created in the order clip, threshold (camera is alone).
export function ensureChild(parent: Element, name: string): Element {
  const existing = childOf(parent, name);
  if (existing) return existing;
  const created = parent.ownerDocument.createElementNS(null, name);
  const before = name === "clip" ? parent.firstElementChild : null;
  parent.insertBefore(created, before);
  return created;
}

export function removeChild(parent: Element, name: string): void {
  childOf(parent, name)?.remove();
}

export function fileOf(doc: XMLDocument): string {
  return layer(doc, "data")?.getAttribute("file") ?? "";
}

export function stepOf(doc: XMLDocument): number {
  return Number(layer(doc, "data")?.getAttribute("step") ?? "0");
}

export function setData(doc: XMLDocument, file: string, step: number): void {
  const data = ensureLayer(doc, "data");
  data.setAttribute("file", file);
  data.setAttribute("step", String(step));
}

export function setViewSize(doc: XMLDocument, width: number, height: number): void {
  const view = ensureLayer(doc, "view");
  view.setAttribute("width", String(width));
  view.setAttribute("height", String(height));
}

// Without a camera the server fits the view to the specimen (a new file),
// or keeps the camera where it is (a replacement).
export function removeCamera(doc: XMLDocument): void {
  const view = layer(doc, "view");
  if (view) removeChild(view, "camera");
}
