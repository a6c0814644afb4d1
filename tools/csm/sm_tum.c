/*
 * sm_tum: time CSM's PL-ICP (sm_icp) over consecutive scan pairs of a CSM log
 * and write the chained trajectory in TUM format. Built by build.sh against
 * CSM (github.com/AndreaCensi/csm); README, Performance, says how it is run.
 *
 * Modelled on CSM's sm/apps/sm3.c:
 *  - parameters from sm_options() defaults, overridable on the command line
 *    (e.g. -laser_x 0.04), input with -in FILE (default stdin);
 *  - all scans are read into memory first (ld_read_all -> ld_read_smart, i.e.
 *    one JSON laser_data object per line); only the matching loop is timed
 *    with clock();
 *  - first guess = odometry difference expressed through the laser pose:
 *        laser_refodom = odom_ref (+) laser, laser_nowodom = odom_now (+) laser,
 *        first_guess   = pose_diff_d(laser_nowodom, laser_refodom)
 *    (algebraically identical to sm3's (-laser) (+) odo_diff (+) laser).
 *
 * stderr: one timing line
 *   "sm_tum: pairs N loop_cpu_s S us_per_pair U iters_per_pair I failed F"
 * stdout: TUM trajectory "t x y z qx qy qz qw" with z = qx = qy = 0 (robot
 *   pose, one line per scan).
 *   Pose of scan 0 = its odometry; pose(i+1) = pose(i) (+) laser (+) x_i (+) (-laser)
 *   where x_i is the ICP result (laser frame); a failed match takes the
 *   odometry increment pose_diff_d(odom_{i+1}, odom_i).
 *   t = timestamp sec + usec * 1e-6.
 */
#include <time.h>
#include <string.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <csm/csm_all.h>
#include <options/options.h>

extern void sm_options(struct sm_params *p, struct option *ops);

static double wrap(double a) {
	while (a > M_PI) a -= 2 * M_PI;
	while (a < -M_PI) a += 2 * M_PI;
	return a;
}

int main(int argc, const char *argv[]) {
	sm_set_program_name(argv[0]);

	const char *input_filename;
	struct sm_params params;
	struct sm_result result;

	struct option *ops = options_allocate(100);
	options_string(ops, "in", &input_filename, "stdin", "Log file");
	sm_options(&params, ops);
	if (!options_parse_args(ops, argc, argv)) {
		fprintf(stderr, "\n\nUsage:\n");
		options_print_help(ops, stderr);
		return -1;
	}

	FILE *file = open_file_for_reading(input_filename);
	if (!file) return -1;

	LDP *lds; int n;
	if (!ld_read_all(file, &lds, &n)) {
		sm_error("Cannot read all laser scans.\n");
		return -1;
	}
	if (n < 2) {
		sm_error("Need at least 2 scans, got %d.\n", n);
		return 1;
	}
	int nbad = 0;
	for (int i = 0; i < n; i++)
		if (!ld_valid_fields(lds[i])) nbad++;
	if (nbad) fprintf(stderr, "sm_tum: warning: %d scans fail ld_valid_fields\n", nbad);

	int npairs = n - 1;
	double (*res)[3] = malloc(sizeof(double[3]) * npairs);
	int *ok = malloc(sizeof(int) * npairs);
	long num_iterations = 0;
	int num_failed = 0;

	/* ---- timed matching loop ---- */
	clock_t start = clock();
	for (int i = 0; i < npairs; i++) {
		params.laser_ref = lds[i];
		params.laser_sens = lds[i + 1];

		double laser_refodom[3], laser_nowodom[3];
		oplus_d(params.laser_ref->odometry, params.laser, laser_refodom);
		oplus_d(params.laser_sens->odometry, params.laser, laser_nowodom);
		pose_diff_d(laser_nowodom, laser_refodom, params.first_guess);

		result.iterations = 0;
		sm_icp(&params, &result);

		num_iterations += result.iterations;
		ok[i] = result.valid;
		if (result.valid) {
			res[i][0] = result.x[0]; res[i][1] = result.x[1]; res[i][2] = result.x[2];
		} else {
			num_failed++;
		}
	}
	clock_t end = clock();
	/* ---- end of timed loop ---- */

	double seconds = (double)(end - start) / CLOCKS_PER_SEC;
	fprintf(stderr,
		"sm_tum: pairs %d loop_cpu_s %.3f us_per_pair %.1f iters_per_pair %.3f failed %d\n",
		npairs, seconds, 1e6 * seconds / npairs,
		(double)num_iterations / npairs, num_failed);

	/* Chain into a robot-frame trajectory. */
	double minus_laser[3];
	ominus_d(params.laser, minus_laser);
	double pose[3];
	copy_d(lds[0]->odometry, 3, pose);
	for (int i = 0; i < n; i++) {
		double t = lds[i]->tv.tv_sec + lds[i]->tv.tv_usec * 1e-6;
		double th = wrap(pose[2]);
		printf("%.6f %.9f %.9f 0 0 0 %.9f %.9f\n", t, pose[0], pose[1],
		       sin(th / 2), cos(th / 2));
		if (i == npairs) break;
		double inc[3];
		if (ok[i]) {
			double tmp[3];
			oplus_d(params.laser, res[i], tmp);
			oplus_d(tmp, minus_laser, inc);
		} else {
			pose_diff_d(lds[i + 1]->odometry, lds[i]->odometry, inc);
		}
		oplus_d(pose, inc, pose);
		pose[2] = wrap(pose[2]);
	}

	for (int i = 0; i < n; i++) ld_free(lds[i]);
	free(lds); free(res); free(ok);
	return 0;
}
