// Equivalent-inertia boxes: the uniform box with a link's mass and principal moments.
//
// A uniform box of mass m and full sides a, b, c has principal moments
//   I1 = m (b^2 + c^2) / 12,  I2 = m (a^2 + c^2) / 12,  I3 = m (a^2 + b^2) / 12
// so a = sqrt(6 (I2 + I3 - I1) / m), b = sqrt(6 (I1 + I3 - I2) / m), c = sqrt(6 (I1 + I2 - I3) / m).
// A tensor that breaks the triangle inequality (not a physical body; rdtfd's checks say so) gives
// a negative square: that side is drawn as 0.

// Eigen-decomposition of a symmetric 3x3 matrix (cyclic Jacobi). m: rows [[a,b,c],[b,d,e],[c,e,f]].
// Returns {values: [l0, l1, l2], vectors: [[x,y,z] x3]} (vectors[k] belongs to values[k]).
export function symmetricEigen(m) {
  const a = m.map((row) => row.slice());
  const v = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
  for (let sweep = 0; sweep < 50; ++sweep) {
    const off = a[0][1] ** 2 + a[0][2] ** 2 + a[1][2] ** 2;
    const scale = a[0][0] ** 2 + a[1][1] ** 2 + a[2][2] ** 2;
    if (off <= 1e-30 * scale || off === 0) break;
    for (const [p, q] of [[0, 1], [0, 2], [1, 2]]) {
      if (a[p][q] === 0) continue;
      const theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
      const t = Math.sign(theta || 1) / (Math.abs(theta) + Math.sqrt(theta * theta + 1));
      const c = 1 / Math.sqrt(t * t + 1);
      const s = t * c;
      for (let k = 0; k < 3; ++k) {  // a <- a J (columns p, q)
        const akp = a[k][p], akq = a[k][q];
        a[k][p] = c * akp - s * akq;
        a[k][q] = s * akp + c * akq;
      }
      for (let k = 0; k < 3; ++k) {  // a <- J^T a (rows p, q)
        const apk = a[p][k], aqk = a[q][k];
        a[p][k] = c * apk - s * aqk;
        a[q][k] = s * apk + c * aqk;
      }
      for (let k = 0; k < 3; ++k) {  // v <- v J
        const vkp = v[k][p], vkq = v[k][q];
        v[k][p] = c * vkp - s * vkq;
        v[k][q] = s * vkp + c * vkq;
      }
    }
  }
  return {
    values: [a[0][0], a[1][1], a[2][2]],
    vectors: [0, 1, 2].map((k) => [v[0][k], v[1][k], v[2][k]]),
  };
}

// inertia: [ixx, ixy, ixz, iyy, iyz, izz] about the centre of mass, link axes; mass > 0.
// Returns {sides: [a, b, c] (m, along axes[0..2]), axes: three unit vectors in the link frame
// (right-handed), moments: [I1, I2, I3]}, or null for a link without mass.
export function equivalentBox(mass, inertia) {
  if (!(mass > 0)) return null;
  const [ixx, ixy, ixz, iyy, iyz, izz] = inertia;
  const { values, vectors } = symmetricEigen([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]);
  const [i1, i2, i3] = values;
  const side = (x) => Math.sqrt(Math.max(0, (6 * x) / mass));
  const axes = vectors.map((u) => u.slice());
  // Right-handed: axes[2] = axes[0] x axes[1].
  const [u, w] = axes;
  axes[2] = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
  return { sides: [side(i2 + i3 - i1), side(i1 + i3 - i2), side(i1 + i2 - i3)], axes, moments: values };
}
