// softevo dashboard: measures with their units, as a reader wants them (no DOM: node can test
// this module alone, tests/api/dashboard/test_units.py). Four significant figures, a unit
// prefix for energy (32113.0923 J reads 32.11 kJ), the unit of the cost of transport, and the
// objectives' names and the Pareto front's axes (scales and ticks).

const missing = (value) => value === null || value === undefined || !Number.isFinite(Number(value));

// a number to 4 significant figures, without an exponent in the range a reader meets
export const significant = (value, digits = 4) => {
  if (missing(value)) return "–";
  const number = Number(value);
  if (number === 0) return "0";
  const text = number.toPrecision(digits);
  if (text.includes("e") && Math.abs(number) >= 1) return String(Number(text));  // 22430, not 2.243e+4
  return text.includes("e") ? text : String(Number(text));
};

// actuator work: J, kJ or MJ
export const energyText = (joules) => {
  if (missing(joules)) return "–";
  const size = Math.abs(Number(joules));
  if (size >= 1e6) return `${significant(joules / 1e6)} MJ`;
  if (size >= 1e3) return `${significant(joules / 1e3)} kJ`;
  return `${significant(joules)} J`;
};

// energy / (mass x g x distance): joules per newton-metre, a pure number
export const costOfTransportText = (value) =>
  missing(value) ? "–" : `${significant(value)} J/(N·m) (dimensionless)`;

// -- objectives (softevo.core.objectives.MEASURES, with what a reader reads for a pure number) --

export const MEASURE_UNITS = {
  speed: "m/s", forward_speed: "m/s", climb_rate: "m/s", distance: "m", efficiency: "m/J",
  cost_of_transport: "dimensionless", energy: "J", heading: "degrees", stable: "0 or 1",
  total_mass: "kg", masses: "count", springs: "count",
};
const PURE = ["dimensionless", "count", "0 or 1"];

// "cost of transport (dimensionless)": a measure named with its unit, never the unit "1"
export const measureLabel = (measure) =>
  `${measure.replace(/_/g, " ")}${MEASURE_UNITS[measure] ? ` (${MEASURE_UNITS[measure]})` : ""}`;

// "speed ↑": an objective of the `objectives` setting in a few characters (↑ maximised)
export const objectiveShort = (spec) => `${spec.measure.replace(/_/g, " ")} ${spec.goal === "min" ? "↓" : "↑"}`;

// "m/s": a hypervolume's unit, the product of its objectives' units without the pure numbers
export const hypervolumeUnit = (specs) => {
  const kept = specs.map((s) => MEASURE_UNITS[s.measure]).filter((u) => u && !PURE.includes(u));
  return kept.length ? kept.join(" × ") : "dimensionless";
};

const quantile = (sorted, q) => {
  const at = (sorted.length - 1) * q, lo = Math.floor(at), hi = Math.ceil(at);
  return sorted[lo] + (sorted[hi] - sorted[lo]) * (at - lo);
};

// How an axis shows its values (core/outputs/front_figure.py's axis_scale): where all the dots
// span more than 5 times what the front and the middle half of the dots span, one outlier would
// squash the front, so the axis is logarithmic (every value positive) or clipped around them.
export function axisScale(values, front) {
  const lo = Math.min(...values), hi = Math.max(...values);
  const linear = { kind: "linear", lo, hi: hi > lo ? hi : lo + 1 };
  if (values.length < 2 || !front.length) return linear;
  const sorted = [...values].sort((a, b) => a - b);
  const low = Math.min(quantile(sorted, 0.25), ...front), high = Math.max(quantile(sorted, 0.75), ...front);
  const reference = high - low;
  if (reference <= 0 || hi - lo <= 5 * reference) return linear;
  if (lo > 0) return { kind: "log", lo, hi };
  return { kind: "clipped", lo: Math.max(lo, low - reference), hi: Math.min(hi, high + reference) };
}

// Tick values of an axis from lo to hi: about `count` round numbers, or the powers of ten (and
// 2 and 5 times them when few) of a logarithmic axis.
export function ticks(scale, count = 5) {
  const { lo, hi } = scale;
  if (scale.kind === "log") {
    const out = [];
    for (let e = Math.floor(Math.log10(lo)); e <= Math.ceil(Math.log10(hi)); e++) {
      for (const m of [1, 2, 5]) out.push(m * 10 ** e);
    }
    const inside = out.filter((v) => v >= lo * 0.999 && v <= hi * 1.001);
    const decades = inside.filter((v) => Math.abs(Math.log10(v) % 1) < 1e-9);
    return decades.length >= 3 ? decades : inside;
  }
  const raw = (hi - lo) / count, power = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((m) => m * power).find((s) => s >= raw) || raw;
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(Number(v.toPrecision(12)));
  return out;
}
