// The Data pane: the files the user may read (ListFiles) and the summary of
// the one chosen (Describe), as the Qt client's file tree and description:
// format and size, N and M, the steps and their times, the arrays (those
// of the first step only), and the file's extra arrays for the panel's
// colour-by lists.
import { el } from "./dom.js";
import type { DescribeResponse, FileEntry } from "./gen/crackvis/v1/data_pb.js";

export interface FileSummary {
  text: string;
  particleExtras: string[];
  bondExtras: string[];
}

const kExtraFolders: ReadonlyArray<readonly [folder: string, kind: "particle" | "bond"]> = [
  ["/extra/particles/", "particle"],
  ["/steps/000000/extra/particles/", "particle"],
  ["/extra/bonds/", "bond"],
  ["/steps/000000/extra/bonds/", "bond"],
];

function megabytes(bytes: bigint): string {
  return `${(Number(bytes) / 1e6).toFixed(1)} MB`;
}

export function summarize(file: string, d: DescribeResponse): FileSummary {
  let particles = "?";
  let bonds = "?";
  const particleExtras: string[] = [];
  const bondExtras: string[] = [];
  const arrays: string[] = [];
  for (const dataset of d.datasets) {
    const path = dataset.path;
    const rows = dataset.shape.length > 0 ? String(dataset.shape[0]) : "?";
    if (path === "/particles/radius") particles = rows;
    if (path === "/bonds/pairs") bonds = rows;
    for (const [folder, kind] of kExtraFolders) {
      if (!path.startsWith(folder)) continue;
      const names = kind === "particle" ? particleExtras : bondExtras;
      const name = path.slice(folder.length);
      if (!names.includes(name)) names.push(name);
    }
    // Per-step arrays repeat in every step: the first step's stand for all.
    if (!path.startsWith("/steps/") || path.startsWith("/steps/000000/")) {
      arrays.push(`${path} ${dataset.dtypeName} [${dataset.shape.join(", ")}]`);
    }
  }
  const steps = d.steps.length;
  const time = (t: number) => String(Number(t.toPrecision(6)));
  const times =
    steps > 0 ? `, t = ${time(d.steps[0].time)} .. ${time(d.steps[steps - 1].time)} s` : "";
  const format = d.format ? `${d.format} v${d.formatVersion}` : "(not crackvis-dem)";
  const text = [
    file,
    `format ${format}, ${megabytes(d.sizeBytes)}`,
    `N = ${particles} particles, M = ${bonds} bonds`,
    `${steps} steps${times}`,
    "",
    ...arrays,
  ].join("\n");
  return { text, particleExtras, bondExtras };
}

export interface FileChoice {
  chosen(file: string): void; // a click: describe it
  opened(file: string): void; // a double click: open it
}

export function showFiles(list: HTMLElement, files: FileEntry[], choice: FileChoice): void {
  list.replaceChildren();
  if (files.length === 0) {
    list.append(el("p", { className: "hint", textContent: "No files you may read." }));
    return;
  }
  for (const entry of files) {
    const item = el(
      "button",
      { type: "button", className: "file", disabled: !entry.isHdf5, title: entry.path },
      el("span", { className: "path", textContent: entry.path }),
      el("span", { className: "size", textContent: megabytes(entry.sizeBytes) }),
    );
    item.dataset.path = entry.path;
    item.addEventListener("click", () => {
      for (const other of Array.from(list.children)) {
        other.classList.toggle("chosen", other === item);
      }
      choice.chosen(entry.path);
    });
    item.addEventListener("dblclick", () => choice.opened(entry.path));
    list.append(item);
  }
}
