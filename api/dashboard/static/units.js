// softevo dashboard: measures with their units, as a reader wants them (no DOM: node can test
// this module alone, tests/api/dashboard/test_units.py). Four significant figures, a unit
// prefix for energy (32113.0923 J reads 32.11 kJ), and the unit of the cost of transport.

const missing = (value) => value === null || value === undefined || !Number.isFinite(Number(value));

// a number to 4 significant figures, without an exponent in the range a reader meets
export const significant = (value, digits = 4) => {
  if (missing(value)) return "–";
  const number = Number(value);
  if (number === 0) return "0";
  const text = number.toPrecision(digits);
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
