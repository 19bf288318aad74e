// Checklist items 5-9: ports, and who may open which socket.
using System;
using Ixxat.Vci3.Bal.Can;
using Ixxat.Vci3.Bal.Lin;
using NUnit.Framework;

namespace Canemu.Tests
{
  public class SocketTests : DaemonFixture
  {
    protected override string Config { get { return Daemon.WithLin; } }

    // Two programs' BALs of `device`: while the first holds the object of type TSocket of `port`
    // (`whileHeld` looks at it then), the second is refused it with a message that says `says`;
    // once the first disposed it, the second gets it.
    static void RefusedWhileHeld<TSocket>(string device, byte port, string says,
                                          Action<TSocket> whileHeld = null)
        where TSocket : class, IDisposable
    {
      using (var one = T.Bal(device))
      using (var two = T.Bal(device))
      {
        var held = T.Open<TSocket>(one, port);
        if (whileHeld != null) whileHeld(held);
        var e = T.Throws(() => two.OpenSocket(port, typeof(TSocket)));
        Assert.AreEqual(0xE001000Au, e.ErrorCode);
        StringAssert.Contains(says, e.Message);
        held.Dispose();
        T.Open<TSocket>(two, port).Dispose();
      }
    }

    [Test]
    public void Item05_PortIndexIsZeroBasedAndBelowResourcesCount()
    {
      using (var bal = T.Bal("gamma"))
      {
        Assert.AreEqual(2, bal.Resources.Count);
        using (var s = T.Open<ICanSocket>(bal, 0)) Assert.AreEqual(0, s.BusPort);
        using (var s = T.Open<ILinSocket>(bal, 1)) Assert.AreEqual("LIN-2", s.BusName);
        var e = T.Throws(() => bal.OpenSocket(2, typeof(ICanSocket)));
        Assert.AreEqual(0xE0010004u, e.ErrorCode);
        StringAssert.Contains("port 2 does not exist", e.Message);
        StringAssert.Contains("ports 0..1", e.Message);
        e = T.Throws(() => bal.OpenSocket(1, typeof(ICanChannel)));
        StringAssert.Contains("port 1 of USB-to-CAN (canemu gamma) is a Lin connection", e.Message);
        e = T.Throws(() => bal.OpenSocket(0, typeof(string)));
        StringAssert.Contains("System.String is no socket type", e.Message);
        e = T.Throws(() => { var r = bal.Resources[5]; });
        StringAssert.Contains("has 2 bus connections", e.Message);
      }
    }

    [Test]
    public void Item06_SocketsOpenWhateverElseIsHeld()
    {
      using (var other = T.Bal("gamma"))
      using (var control = T.Open<ICanControl>(other))
      using (var exclusive = T.Open<ICanChannel>(other))
      using (var linControl = T.Open<ILinControl>(other, 1))
      using (var bal = T.Bal("gamma"))
      {
        exclusive.Initialize(16, 16, true);
        control.InitLine(CanOperatingModes.Standard, CanBitrate.Cia250KBit);
        for (int i = 0; i < 3; i++)
        {
          using (var socket = T.Open<ICanSocket>(bal))
          {
            Assert.IsTrue(socket.SupportsDelayedTransmission);
            Assert.AreEqual(CanBitrate.Cia250KBit, socket.LineStatus.Bitrate);
            Assert.IsTrue(socket.LineStatus.IsInInitMode);
          }
        }
        using (var lin = T.Open<ILinSocket>(bal, 1))
        {
          Assert.IsTrue(lin.SupportsMasterMode);
          Assert.IsTrue(lin.LineStatus.IsInInitMode);
        }
        // Everything of the port held: the socket still opens; asking then says why not.
        using (var scheduler = T.Open<ICanScheduler>(other))
        using (var socket = T.Open<ICanSocket>(bal))
        {
          var e = T.Throws(() => { var x = socket.ClockFrequency; });
          Assert.AreEqual(0xE001000Au, e.ErrorCode);
          StringAssert.Contains("other programs hold every object of CAN port 0", e.Message);
          Assert.AreEqual(1000000u, scheduler.ClockFrequency);
        }
      }
    }

    [Test]
    public void Item07_ASecondControlUnitIsRefusedWhileOneIsHeld()
    {
      RefusedWhileHeld<ICanControl>("gamma", 0,
          "the control unit of CAN port 0 of USB-to-CAN (canemu gamma) is in use by another program");
      RefusedWhileHeld<ILinControl>("gamma", 1, "the control unit of LIN port 1");
    }

    [Test]
    public void Item08_ASecondCyclicListIsRefusedWhileOneIsHeld()
    {
      RefusedWhileHeld<ICanScheduler>("alpha", 0,
          "the cyclic transmit list of CAN port 0 of USB-to-CAN (canemu alpha) is in use",
          list => Assert.IsTrue(list.SupportsCyclicMessageScheduler));
      // Every emulated IXXAT controller has the list, so NotImplementedException (a port without
      // one) cannot occur: docs/dotnet.md.
    }

    [Test]
    public void Item09_ClosingTheControlKeepsTheSettingsWhileAChannelIsOpen()
    {
      using (var a = new Line("alpha", bitrate: CanBitrate.Cia250KBit))
      using (var b = new Line("beta", bitrate: CanBitrate.Cia250KBit))
      {
        a.Control.Dispose();
        var status = a.Channel.LineStatus;
        Assert.AreEqual(CanBitrate.Cia250KBit, status.Bitrate);
        Assert.IsFalse(status.IsInInitMode, "still online");
        a.Send(T.Msg(0x10, 1));
        T.Step(2);
        Assert.AreEqual(1, b.Data().Count);
        // A new control unit finds the line as it was left.
        using (var again = T.Open<ICanControl>(a.Bal))
        {
          Assert.AreEqual(CanBitrate.Cia250KBit, again.LineStatus.Bitrate);
          Assert.IsFalse(again.LineStatus.IsInInitMode);
        }
      }
    }
  }
}
