// A peer for the scale table: Enki (Debian's libenki-dev) running the
// crossing scene's starts and goals with a go-to-goal controller, one
// thread. Built and run by enki_peer.sh; not part of mrsim.
//
// Usage: enki_peer PLACES DT STEPS MAX_SPEED RADIUS TOLERANCE
// PLACES: one robot a line, "sx sy gx gy". Prints one line of key=value.

#include <enki/PhysicalEngine.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <string>
#include <vector>

namespace {

// A disc that sets its velocity towards its goal each control step (the
// velocity of mrsim's `homing` planner: straight at the goal, at most
// max_speed, stopping inside the tolerance).
class Homing : public Enki::PhysicalObject {
public:
	Homing(double sx, double sy, double gx, double gy, double max_speed, double tolerance)
		: start(sx, sy), goal(gx, gy), maxSpeed(max_speed), tolerance(tolerance) {}

	bool atGoal() const { return (goal - pos).norm() <= tolerance; }
	double travelled() const { return (pos - start).norm(); }

protected:
	void controlStep(double dt) override {
		Enki::Vector d = goal - pos;
		double n = d.norm();
		if (n <= tolerance) {
			speed = Enki::Vector(0, 0);
		} else {
			double s = std::min(maxSpeed, n / dt);
			speed = d * (s / n);
		}
		PhysicalObject::controlStep(dt);
	}

private:
	Enki::Point start;
	Enki::Point goal;
	double maxSpeed;
	double tolerance;
};

double cpuSeconds() {
	timespec t{};
	clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
	return t.tv_sec + t.tv_nsec * 1e-9;
}

}  // namespace

int main(int argc, char** argv) {
	if (argc != 7) {
		std::fprintf(stderr, "usage: %s PLACES DT STEPS MAX_SPEED RADIUS TOLERANCE\n", argv[0]);
		return 2;
	}
	const double dt = std::atof(argv[2]);
	const long steps = std::atol(argv[3]);
	const double maxSpeed = std::atof(argv[4]);
	const double radius = std::atof(argv[5]);
	const double tolerance = std::atof(argv[6]);
	std::ifstream in(argv[1]);
	if (!in || dt <= 0 || steps <= 0) {
		std::fprintf(stderr, "cannot read %s, or DT/STEPS not positive\n", argv[1]);
		return 2;
	}
	// No walls: the crossing's arena is far beyond where its robots go.
	Enki::World world;
	std::vector<Homing*> robots;
	double sx, sy, gx, gy;
	while (in >> sx >> sy >> gx >> gy) {
		auto* r = new Homing(sx, sy, gx, gy, maxSpeed, tolerance);
		r->setCylindric(radius, 1.0, 1.0);
		r->pos = Enki::Point(sx, sy);
		r->dryFrictionCoefficient = 0;
		r->viscousFrictionCoefficient = 0;
		r->viscousMomentFrictionCoefficient = 0;
		world.addObject(r);
		robots.push_back(r);
	}
	if (robots.empty()) {
		std::fprintf(stderr, "no robots in %s\n", argv[1]);
		return 2;
	}
	const double cpu0 = cpuSeconds();
	const auto wall0 = std::chrono::steady_clock::now();
	for (long k = 0; k < steps; ++k) world.step(dt);
	const double wall =
		std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
	const double cpu = cpuSeconds() - cpu0;
	long arrived = 0;
	double travelled = 0;
	for (auto* r : robots) {
		arrived += r->atGoal();
		travelled += r->travelled();
	}
	const double sim = steps * dt;
	std::printf(
		"robots=%zu steps=%ld sim_s=%.3f wall_s=%.3f cpu_s=%.3f rtf_wall=%.4g rtf_cpu=%.4g "
		"cpu_us_per_robot_step=%.3g at_goal=%ld mean_travelled_m=%.3f\n",
		robots.size(), steps, sim, wall, cpu, sim / wall, sim / cpu,
		cpu * 1e6 / (double(steps) * robots.size()), arrived, travelled / robots.size());
	return 0;
}
