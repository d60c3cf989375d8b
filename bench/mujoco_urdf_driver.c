/* MuJoCo's side of bench/urdf_race.py (issue 40): one fresh process that compiles a URDF
 * (mj_loadXML), sets the start state, takes NSTEPS RK4 steps of 1/NSTEPS s and prints qpos,
 * what a C user of MuJoCo pays for "load this robot and simulate one second".
 *
 *   mujoco_urdf_driver ROBOT.urdf NSTEPS STATE.txt
 * STATE.txt: nq numbers (qpos), then nv numbers (qvel), in MuJoCo's order.
 * stdout: qpos after 1 s (%.17g, one line); stderr: "compile S simulate S" (seconds).
 * Built by urdf_race.py against the headers and libmujoco.so of the mujoco wheel (-O2). */
#include <mujoco/mujoco.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char** argv) {
  if (argc != 4) {
    fprintf(stderr, "usage: %s ROBOT.urdf NSTEPS STATE.txt\n", argv[0]);
    return 1;
  }
  const long nsteps = atol(argv[2]);
  char err[1000] = "";
  const double t0 = now();
  mjModel* m = mj_loadXML(argv[1], NULL, err, sizeof err);
  if (!m) {
    fprintf(stderr, "mj_loadXML: %s\n", err);
    return 1;
  }
  mjData* d = mj_makeData(m);
  const double t1 = now();
  FILE* f = fopen(argv[3], "r");
  if (!f) return 1;
  for (int i = 0; i < m->nq; ++i)
    if (fscanf(f, "%lf", &d->qpos[i]) != 1) return 1;
  for (int i = 0; i < m->nv; ++i)
    if (fscanf(f, "%lf", &d->qvel[i]) != 1) return 1;
  fclose(f);
  m->opt.integrator = mjINT_RK4;
  m->opt.timestep = 1.0 / (double)nsteps;
  const double t2 = now();
  for (long k = 0; k < nsteps; ++k) mj_step(m, d);
  const double t3 = now();
  for (int i = 0; i < m->nq; ++i) printf(i ? " %.17g" : "%.17g", d->qpos[i]);
  printf("\n");
  fprintf(stderr, "compile %.9f simulate %.9f\n", t1 - t0, t3 - t2);
  mj_deleteData(d);
  mj_deleteModel(m);
  return 0;
}
