"""A study over any fields: speed × the dampers' stiffness on the fast converged model, with
the uncontrolled run as reference, the deck acceleration and ride comfort among the indices."""

import vtb

cfg = vtb.paper_config(model="fast", calibrated=True)
cfg.tids = vtb.tids_around(cfg)  # ten rail–slab TIDs around mid-span
st = vtb.study(cfg, {"speed": [70.0, 80.0], "tids.k_t": [1e8, 2e8]}, reference={"tids": None},
               indices=["rail_acc_max", "bridge_acc_max", "car_comfort_aw"], progress=False)
print(st.to_pandas().drop(columns="error").to_string(index=False, float_format="%.4g"))
print("lowest a_rm:", st.best("rail_acc_max"))
