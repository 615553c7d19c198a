"""Vehicle–bridge interaction with a quarter car (docs/vehicles.md): the dynamic amplification
of a 32 m simply supported girder's midspan deflection under a moving force and under a quarter
car of the same weight (a sprung mass on its suspension over a wheel on a Hertz spring), and the
quarter car's largest body acceleration and contact-force change, over a range of speeds.

    python examples/quarter_car.py
"""

import math

import vtb

L, RHO, AREA, E, INERTIA = 32.0, 2500.0, 8.75, 3.945e10, 9.25  # the article's girder
SPRUNG, WHEEL = 13_600.0, 2_400.0  # kg: a quarter of a high-speed car


def main():
    weight = (SPRUNG + WHEEL) * 9.81
    static = weight * L**3 / (48 * E * INERTIA)
    print("speed (m/s) | DAF moving force | DAF quarter car | body acc (m/s²) | contact force (% static)")
    for speed in (40.0, 60.0, 80.0, 100.0, 120.0):
        t_end = L / speed
        dt = t_end / math.ceil(t_end / 5e-5)
        cfg = vtb.moving_load_config(L, RHO, AREA, E, INERTIA, [vtb.MovingForce(weight, 0.0)], speed, modes=20,
                                     dt=dt, t_end=t_end, points=[L / 2])
        force = vtb.simulate(cfg, progress=False)
        cfg.forces = []
        cfg.vehicles = [vtb.Vehicle.quarter_car(SPRUNG, WHEEL, stiffness=1.0e6, damping=4.0e4, x_front=0.0, rails=1)]
        car = vtb.simulate(cfg, progress=False)
        daf = [(r.displacement("beam") - r.displacement("beam")[0]).max() / static for r in (force, car)]
        body = abs(car.vehicle_acc[:, 0, 0]).max()
        swing = 100 * abs(car.contact_force[:, 0] / weight - 1).max()
        print(f"{speed:11.0f} | {daf[0]:16.3f} | {daf[1]:15.3f} | {body:15.3f} | {swing:24.2f}")


if __name__ == "__main__":
    main()
