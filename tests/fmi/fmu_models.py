"""The pendulums the FMU tests export, written once: chains of revolute joints about z and
rods hanging from the world, with a test's own inputs, parameters, outputs and equations."""


def link(joint, rod, L=1, m=1, q=None, u=None, **modifiers):
    """A revolute joint about z (q, u: its starts; modifiers such as q_min, q_max) and the rod it turns."""
    starts = "".join(f", {k}(start = {v})" for k, v in (("q", q), ("u", u)) if v is not None)
    rest = "".join(f", {k} = {v}" for k, v in modifiers.items())
    return joint, rod, f"Revolute {joint}(axis = {{0, 0, 1}}{starts}{rest});", f"Rod {rod}(L = {L}, m = {m});"


def pendulums(name, comment, chains, declarations=(), outputs=(), equations=(), annotation=None):
    """The model's text: each chain (a list of links) hangs from the world, a link's joint on the
    previous rod's tip; `declarations` (inputs, parameters) before the world, `outputs` after the
    links, `equations` after the connections."""
    parts, connects = [], []
    for chain in chains:
        parent = "world.frame_b"
        for joint, rod, joint_line, rod_line in chain:
            parts += [joint_line, rod_line]
            connects += [f"connect({parent}, {joint}.frame_a);", f"connect({joint}.frame_b, {rod}.frame_a);"]
            parent = f"{rod}.frame_b"
    body = [*declarations, "World world;", *parts, *outputs]
    tail = [*connects, *equations] + ([f"annotation(experiment({annotation}));"] if annotation else [])
    lines = [f'model {name} "{comment}"', *("  " + x for x in body), "equation", *("  " + x for x in tail)]
    return "\n" + "\n".join(lines) + f"\nend {name};\n"


def single_pendulum(name, comment, q=0.3, u=None, **parts):
    """hinge and rod (1 m, 1 kg), from q = 0.3 at rest unless told; `parts` as pendulums()'s."""
    limits = {k: parts.pop(k) for k in ("q_min", "q_max") if k in parts}
    return pendulums(name, comment, [[link("hinge", "rod", q=q, u=u, **limits)]], **parts)


def double_pendulum(name, comment, q1, u1, q2, u2, **parts):
    """j1 with rod1 (1 m, 1 kg), then j2 with rod2 (0.7 m, 0.6 kg) at its tip; `parts` as pendulums()'s."""
    return pendulums(name, comment, [[link("j1", "rod1", 1, 1, q1, u1), link("j2", "rod2", 0.7, 0.6, q2, u2)]],
                     **parts)
