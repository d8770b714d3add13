// The robot as shaded voxels that deform with its masses: every outer voxel face (a quad of four
// mass indices from the replay, wound outward) drawn as two triangles, coloured by material, or
// by its voxel's own phase for a co-designed robot, and lit, so the body reads as a solid.
import * as THREE from "three";

const MATERIALS = { soft: "#9bc59d", hard: "#4a4f55", sine: "#d1495b", neg_sine: "#2f6fb5", filled: "#8d98a3" };

export function voxelMesh(data, byHue) {
  const faces = data.faces, n = faces.length;
  const phases = data.robot && data.robot.phases, c = (data.robot && data.robot.actuation && data.robot.actuation.c) || 0;
  const positions = new Float32Array(n * 6 * 3);
  const colours = new Float32Array(n * 6 * 3);
  faces.forEach((_, f) => {
    const material = data.face_materials[f];
    const phase = phases ? phases[data.face_voxels[f]] : null;
    const colour = byHue && phase !== null && phase !== undefined && material in { sine: 1, neg_sine: 1 }
      ? new THREE.Color().setHSL(((((c + phase + (material === "neg_sine" ? Math.PI : 0)) / (2 * Math.PI)) % 1) + 1) % 1, 0.75, 0.5)
      : new THREE.Color(MATERIALS[material] || MATERIALS.filled);
    for (let k = 0; k < 6; k++) colours.set([colour.r, colour.g, colour.b], (f * 6 + k) * 3);
  });
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.BufferAttribute(positions, 3));
  geometry.setAttribute("color", new THREE.BufferAttribute(colours, 3));
  const mesh = new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide }));
  const corners = [0, 1, 2, 0, 2, 3];  // a quad's two triangles, outward like the quad
  const update = (points) => {
    faces.forEach((quad, f) => corners.forEach((k, j) => positions.set(points[quad[k]], (f * 6 + j) * 3)));
    geometry.attributes.position.needsUpdate = true;
    geometry.computeVertexNormals();
  };
  return { mesh, update, faces: n };
}
