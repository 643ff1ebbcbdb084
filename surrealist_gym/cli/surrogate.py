"""`surrealist surrogate train|eval`: train a surrogate model on evaluation stores, or measure one on held-out stores.

    surrealist surrogate train results/paper/rq1-seed1-rep[0-7].sqlite --out models/rq1-seed1
    surrealist surrogate eval models/rq1-seed1 results/paper/rq1-seed1-rep8.sqlite results/paper/rq1-seed1-rep9.sqlite
"""
from __future__ import annotations

from ..errors import SurrealistError


def add_arguments(parser) -> None:
    """Arguments of ``surrealist surrogate train`` and ``surrealist surrogate eval``."""
    sub = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    train = sub.add_parser("train", help="train a model on one or more evaluation stores",
                           description="train a model on one or more evaluation stores (.sqlite)")
    train.add_argument("stores", nargs="+", metavar="STORE", help="evaluation stores of one problem")
    train.add_argument("--out", required=True, metavar="DIR", help="model folder to write (weights.pt, meta.json): "
                       "new or empty unless --overwrite")
    train.add_argument("--overwrite", action="store_true", help="replace the model an existing --out holds")
    train.add_argument("--problem", default="replicate", choices=["replicate", "generate"],
                       help="what the stores searched: replicate (features against the mission and the reference "
                            "flight) or generate (default replicate)")
    train.add_argument("--seed", default=None, metavar="TEST.yaml",
                       help="the problem's seed test, for its mission (default: replicate: rq1-seed1.yaml; generate: "
                            "rq2-seed.yaml, both bundled)")
    train.add_argument("--log", default=None, help="reference flight log (replicate; default: the seed's, or case0)")
    train.add_argument("--lowfi", action="store_true",
                       help="add the outcomes of a low-fidelity flight of each test to its features (multi-fidelity; "
                            "~0.1 s of CPU per test)")
    train.add_argument("--kind", default="ensemble", choices=["ensemble", "knn"],
                       help="MLP ensemble (torch) or the k-nearest-neighbours baseline (default ensemble)")
    train.add_argument("--target", default="fitness", choices=["fitness", "min_distance", "unsafe", "crash"],
                       help="what to predict (default fitness)")
    train.add_argument("--members", type=int, default=None, help="ensemble members (default 5)")
    train.add_argument("--epochs", type=int, default=None, help="ensemble training steps (default 300)")
    train.add_argument("--k", type=int, default=None, help="neighbours of the knn baseline (default 7)")
    train.add_argument("--holdout", type=int, default=0, metavar="N",
                       help="first train without the last N stores and report how well it predicts them")
    train.add_argument("--random-seed", type=int, default=0, metavar="N", help="seed of the training (default 0)")
    ev = sub.add_parser("eval", help="measure a model on evaluation stores it was not trained on",
                        description="held-out R2, Spearman rank correlation and calibration of a model")
    ev.add_argument("model", metavar="MODEL", help="model folder written by `surrealist surrogate train`")
    ev.add_argument("stores", nargs="+", metavar="STORE", help="evaluation stores of the model's problem")
    ev.add_argument("--plot", default=None, metavar="PNG",
                    help="also draw predicted vs true values and the calibration of the uncertainty to this PNG")


def _print_metrics(label: str, m: dict, log_scale: bool) -> None:
    modelled = f" ({m['r2_modelled']:.3f} on the model's log scale)" if log_scale else ""
    print(f"{label}: {m['n']} evaluations, R2 {m['r2']:.3f}{modelled}, Spearman {m['spearman']:.3f}, "
          f"MAE {m['mae']:.3g}; "
          f"calibration: {m['within_1sd']:.0%} within 1 sd (68% ideal), {m['within_2sd']:.0%} within 2 sd "
          f"(95% ideal), NLL {m['nll']:.3f}")


def _check_inputs(args) -> None:
    """Every path of the command line, before anything is loaded or trained: the stores are existing, non-empty
    regular files (never created or changed: they are opened read-only), the model a folder, and what is written
    can be written."""
    from pathlib import Path

    from ..errors import regular_file
    from .options import check_at_least, check_writable

    for store in args.stores:
        regular_file(store, "evaluation store", empty_ok=False)
    args.stores = _distinct_stores(args.stores)
    if args.action == "eval":
        if args.plot:
            check_writable(args.plot, "--plot", "file", (".png",))
        model = Path(args.model)
        if not model.is_dir():
            raise SurrealistError(f"{model}: not a surrogate model (expected the folder `surrealist surrogate "
                                  f"train` writes)")
        for name in ("meta.json", "weights.pt"):
            regular_file(model / name, "surrogate model file")
    else:
        check_at_least(args, members=1, epochs=1, k=1, holdout=0, random_seed=0)
        for flag, value, applies, why in (
                ("--log", args.log, args.problem == "replicate", "applies only to --problem replicate (its flight)"),
                ("--k", args.k, args.kind == "knn", "applies only to --kind knn"),
                ("--members", args.members, args.kind == "ensemble", "applies only to --kind ensemble"),
                ("--epochs", args.epochs, args.kind == "ensemble", "applies only to --kind ensemble")):
            if value is not None and not applies:
                raise SurrealistError(f"{flag}: {why}")
        if args.holdout and not args.holdout < len(args.stores):
            raise SurrealistError(f"--holdout {args.holdout}: " + (
                f"expected 1 to {len(args.stores) - 1} (stores given: {len(args.stores)})" if len(args.stores) > 1
                else "needs at least 2 stores, one to train on and one to hold out (given: 1)"))
        out = Path(args.out)
        held = sorted(p.name for p in out.iterdir()) if out.is_dir() else []
        if held and not args.overwrite:  # before check_writable's probe, which would touch the folder
            raise SurrealistError(f"--out {out}: " + ("holds a model already" if "meta.json" in held else
                                                      f"not empty (holds {held[0]})")
                                  + "; --overwrite replaces it, or choose another folder")
        check_writable(args.out, "--out", "folder")


def _distinct_stores(stores: list[str]) -> list[str]:
    """Each store once, by its resolved path (two names for one store would count it twice, and with --holdout
    measure the held-out R2 on training data): a store given again is dropped with a warning."""
    import warnings
    from pathlib import Path

    first: dict = {}
    for store in stores:
        seen = first.setdefault(Path(store).resolve(), store)
        if seen != store:
            warnings.warn(f"{store}: the same store as {seen}, read once", stacklevel=2)
    return list(first.values())


def run(args) -> int:
    """Train a model on the stores, or measure one on held-out stores; returns the exit code."""
    import warnings

    import numpy as np

    _check_inputs(args)

    from surrealist_gym.evaluation import describe_noise
    from surrogates.dataset import Featurizer, load_dataset
    from surrogates.models import SurrogateModel, evaluate_model, predict_dataset

    if args.action == "eval":
        model = SurrogateModel.load(args.model)
        predicted = predict_dataset(model, load_dataset(args.stores, model.featurizer))
        label = f"{args.model} ({model.kind}, {model.target})"
        _print_metrics(label, predicted.metrics(), model.log_scale)
        if args.plot:
            from surrogates.plots import plot_predictions
            try:
                print(f"plot: {plot_predictions(args.plot, model, predicted, label)}")
            except OSError as err:
                raise SurrealistError(f"{args.plot}: cannot write the plot ({err.strerror or err})") from err
        return 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        featurizer = Featurizer.for_problem(args.problem, args.seed, args.log, lowfi=args.lowfi)
    if args.lowfi:
        print("featurizing with one low-fidelity flight per stored test (~0.1 s each) ...", flush=True)
    data = load_dataset(args.stores, featurizer)
    options = {"members": args.members, "epochs": args.epochs} if args.kind == "ensemble" else {"k": args.k}
    config = {k: v for k, v in options.items() if v is not None}
    metrics = {}
    if args.holdout:
        held = np.arange(len(args.stores) - args.holdout, len(args.stores))
        trial = SurrogateModel(featurizer, args.kind, args.target, config, args.random_seed)
        trial.fit_dataset(data.subset(~np.isin(data.groups, held)))
        metrics = evaluate_model(trial, data.subset(np.isin(data.groups, held)))
        _print_metrics(f"held-out ({args.holdout} of {len(args.stores)} stores)", metrics, trial.log_scale)
    model = SurrogateModel(featurizer, args.kind, args.target, config, args.random_seed).fit_dataset(data)
    model.metrics = {"holdout": metrics} if metrics else {}
    model.metrics["train"] = evaluate_model(model, data)
    _print_metrics("training set", model.metrics["train"], model.log_scale)
    out = model.save(args.out)
    print(f"model ({args.kind}, {args.target}, {len(model.train_y)} evaluations flown with "
          f"{describe_noise(data.common_noise)}, {data.X.shape[1]} features) in {out}/: weights.pt, meta.json")
    if args.lowfi and args.target == "fitness":
        from surrogates.prescreen import PrescreenConfig
        from surrogates.replay import model_margin

        rate = PrescreenConfig().miss_rate
        margin = model_margin(model, rate)
        print("pre-screening with it (--surrogate): " + (
            f"skips a candidate whose low-fidelity fitness falls short of the incumbent's by more than {margin:.2f} "
            f"(exceeded by {rate:.0%} of the stores' improvements)" if margin is not None else
            "too few improvements in the stores to calibrate a low-fidelity margin; the EI rule is used"))
    return 0
