"""liedyn as a PyTorch autograd function: the backward pass is liedyn's adjoint.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/torch_adam.py \
        problems/scenes/optimization/rod_throw_friction.json

`SimulationLoss.apply(gamma, problem)` is the scene's loss as a differentiable function of a
torch tensor γ; autograd's backward returns dg/dγ from one adjoint pass (no finite
differences, no unrolled graph). Here torch.optim.Adam minimises it, and the script checks that
autograd's gradient is the one loss_and_gradient returns. Exits 1 if Adam does not bring the
normalised loss under the scene's target.
"""

import sys

import numpy as np
import torch

import liedyn


class SimulationLoss(torch.autograd.Function):
    """g(γ) of a liedyn.DifferentiableProblem, with the adjoint gradient as its backward."""

    @staticmethod
    def forward(ctx, gamma, problem):
        loss, gradient = problem.loss_and_gradient(gamma.detach().cpu().numpy().astype(np.float64))
        ctx.save_for_backward(torch.from_numpy(gradient).to(gamma))
        return gamma.new_tensor(loss)

    @staticmethod
    def backward(ctx, grad_output):
        (gradient,) = ctx.saved_tensors
        return grad_output * gradient, None  # nothing flows to `problem`


def main(path, iterations=100, learning_rate=0.05):
    problem = liedyn.DifferentiableProblem(liedyn.Scene.from_file(path))
    gamma = torch.tensor(problem.gamma0, dtype=torch.float64, requires_grad=True)

    # autograd's gradient is the adjoint's.
    loss = SimulationLoss.apply(gamma, problem)
    loss.backward()
    _, adjoint = problem.loss_and_gradient(problem.gamma0)
    assert np.array_equal(gamma.grad.numpy(), adjoint), "autograd's gradient differs"

    optimizer = torch.optim.Adam([gamma], lr=learning_rate)
    scale = problem.loss_scale
    for i in range(iterations):
        optimizer.zero_grad()
        loss = SimulationLoss.apply(gamma, problem)
        loss.backward()
        optimizer.step()
        if i % 50 == 0:
            print(f"iteration {i}: normalized loss {loss.item() / scale:.3e}")
    normalized = problem.loss(gamma.detach().numpy()) / scale
    reached = normalized <= problem.target_normalized_loss
    print(f"{path}: Adam, {iterations} iterations: normalized loss {normalized:.3e} "
          f"(target {problem.target_normalized_loss:g}: {'reached' if reached else 'NOT reached'})")
    return 0 if reached else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
